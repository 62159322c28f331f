"""What is said of a mission without running it: the lint, the JSON Schema, the node help."""
