"""thymio-bt's control-flow nodes: composites, decorators, their contract, and ticking a tree."""
