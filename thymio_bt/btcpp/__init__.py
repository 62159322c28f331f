"""BehaviorTree.CPP 4 compatibility: XML in and out, the .btlog, the Groot2 monitor, and (in
``runtime``) BT.CPP's built-in nodes and script language, tick for tick."""
