"""BT.CPP 4's built-in nodes and script language, tick for tick, as registered node kinds."""
