"""Where each built-in node lives: its YAML name -> ``"module:attr"``, read without importing it.

The registry imports a node's module the first time a mission names the node, so a run imports and
builds only its own nodes' classes and parameter models, not every family's (their class creation
was most of the start-up of ``thymio-bt run``). ``attr`` is the node's class, or the tuple of
generated classes that holds it (BT.CPP's control nodes), found there by YAML name. Everything else
about a node is declared on its class; this table only says where the class is, in the order
``thymio-bt behaviours`` lists them, and ``tests/test_builtin_nodes.py`` holds it equal to the node
classes the packages define.

    >>> BUILTIN_NODES["MoveUntilWall"], BUILTIN_NODES["bt_sequence"]
    ('thymio_bt.behaviours.motion:MoveUntilWall', 'thymio_bt.btcpp.runtime.control:BTCPP_CONTROL')
"""

from __future__ import annotations

#: every built-in node: YAML name -> "module:attr" (its class, or the tuple holding it)
BUILTIN_NODES: dict[str, str] = {
    "MoveUntilWall": "thymio_bt.behaviours.motion:MoveUntilWall",
    "MoveDistance": "thymio_bt.behaviours.motion:MoveDistance",
    "TurnAngle": "thymio_bt.behaviours.motion:TurnAngle",
    "Stop": "thymio_bt.behaviours.motion:Stop",
    "Wait": "thymio_bt.behaviours.motion:Wait",
    "DeleteEntity": "thymio_bt.behaviours.entities:DeleteEntity",
    "SpawnEntity": "thymio_bt.behaviours.entities:SpawnEntity",
    "ChooseTurn": "thymio_bt.behaviours.maze:ChooseTurn",
    "LookAround": "thymio_bt.behaviours.maze:LookAround",
    "WallAhead": "thymio_bt.behaviours.maze:WallAhead",
    "SideOpen": "thymio_bt.behaviours.maze:SideOpen",
    "IsDeadEnd": "thymio_bt.behaviours.maze:IsDeadEnd",
    "WallFollow": "thymio_bt.behaviours.wall_follow:WallFollow",
    "GoToPose": "thymio_bt.behaviours.navigation:GoToPose",
    "FollowWaypoints": "thymio_bt.behaviours.navigation:FollowWaypoints",
    "WaypointsDone": "thymio_bt.behaviours.navigation:WaypointsDone",
    "ObstacleAhead": "thymio_bt.behaviours.navigation:ObstacleAhead",
    "TurnUntilClear": "thymio_bt.behaviours.navigation:TurnUntilClear",
    "TurnBack": "thymio_bt.behaviours.navigation:TurnBack",
    "SetBlackboard": "thymio_bt.behaviours.navigation:SetBlackboard",
    "MapWalls": "thymio_bt.behaviours.mapping:MapWalls",
    "PlanMove": "thymio_bt.behaviours.mapping:PlanMove",
    "MoveCells": "thymio_bt.behaviours.move_cells:MoveCells",
    "WallMapped": "thymio_bt.behaviours.mapping:WallMapped",
    "AtTarget": "thymio_bt.behaviours.mapping:AtTarget",
    "OutsideMaze": "thymio_bt.behaviours.places:OutsideMaze",
    "InRegion": "thymio_bt.behaviours.places:InRegion",
    "sequence": "thymio_bt.behaviours.flow.composites:Sequence",
    "reactive_sequence": "thymio_bt.behaviours.flow.composites:ReactiveSequence",
    "selector": "thymio_bt.behaviours.flow.composites:Selector",
    "reactive_selector": "thymio_bt.behaviours.flow.composites:ReactiveSelector",
    "parallel": "thymio_bt.behaviours.flow.composites:Parallel",
    "repeat": "thymio_bt.behaviours.flow.decorators:Repeat",
    "retry": "thymio_bt.behaviours.flow.decorators:Retry",
    "timeout": "thymio_bt.behaviours.flow.decorators:Timeout",
    "delay": "thymio_bt.behaviours.flow.decorators:Delay",
    "invert": "thymio_bt.behaviours.flow.decorators:Invert",
    "force_success": "thymio_bt.behaviours.flow.decorators:ForceSuccess",
    "force_failure": "thymio_bt.behaviours.flow.decorators:ForceFailure",
    "until": "thymio_bt.behaviours.flow.decorators:Until",
    "guard": "thymio_bt.behaviours.flow.decorators:Guard",
    "one_shot": "thymio_bt.behaviours.flow.decorators:OneShot",
    "bt_sequence": "thymio_bt.btcpp.runtime.control:BTCPP_CONTROL",
    "bt_sequence_with_memory": "thymio_bt.btcpp.runtime.control:BTCPP_CONTROL",
    "bt_reactive_sequence": "thymio_bt.btcpp.runtime.control:BTCPP_CONTROL",
    "bt_fallback": "thymio_bt.btcpp.runtime.control:BTCPP_CONTROL",
    "bt_reactive_fallback": "thymio_bt.btcpp.runtime.control:BTCPP_CONTROL",
    "bt_parallel": "thymio_bt.btcpp.runtime.control:BTCPP_CONTROL",
    "bt_parallel_all": "thymio_bt.btcpp.runtime.control:BTCPP_CONTROL",
    "bt_if_then_else": "thymio_bt.btcpp.runtime.control:BTCPP_CONTROL",
    "bt_while_do_else": "thymio_bt.btcpp.runtime.control:BTCPP_CONTROL",
    "bt_inverter": "thymio_bt.btcpp.runtime.control:BTCPP_CONTROL",
    "bt_force_success": "thymio_bt.btcpp.runtime.control:BTCPP_CONTROL",
    "bt_force_failure": "thymio_bt.btcpp.runtime.control:BTCPP_CONTROL",
    "bt_keep_running_until_failure": "thymio_bt.btcpp.runtime.control:BTCPP_CONTROL",
    "bt_repeat": "thymio_bt.btcpp.runtime.control:BTCPP_CONTROL",
    "bt_retry_until_successful": "thymio_bt.btcpp.runtime.control:BTCPP_CONTROL",
    "bt_run_once": "thymio_bt.btcpp.runtime.control:BTCPP_CONTROL",
    "bt_timeout": "thymio_bt.btcpp.runtime.control:BTCPP_CONTROL",
    "bt_delay": "thymio_bt.btcpp.runtime.control:BTCPP_CONTROL",
    "bt_precondition": "thymio_bt.btcpp.runtime.control:BTCPP_SCRIPTED",
    "bt_switch2": "thymio_bt.btcpp.runtime.control:BTCPP_SCRIPTED",
    "bt_switch3": "thymio_bt.btcpp.runtime.control:BTCPP_SCRIPTED",
    "bt_switch4": "thymio_bt.btcpp.runtime.control:BTCPP_SCRIPTED",
    "bt_switch5": "thymio_bt.btcpp.runtime.control:BTCPP_SCRIPTED",
    "bt_switch6": "thymio_bt.btcpp.runtime.control:BTCPP_SCRIPTED",
    "bt_conditions": "thymio_bt.btcpp.runtime.control:BTCPP_SCRIPTED",
    "bt_script": "thymio_bt.btcpp.runtime.scripted:Script",
    "bt_script_condition": "thymio_bt.btcpp.runtime.scripted:ScriptCondition",
    "bt_set_blackboard": "thymio_bt.btcpp.runtime.scripted:SetBlackboard",
    "bt_unset_blackboard": "thymio_bt.btcpp.runtime.scripted:UnsetBlackboard",
    "bt_always_success": "thymio_bt.btcpp.runtime.scripted:AlwaysSuccess",
    "bt_always_failure": "thymio_bt.btcpp.runtime.scripted:AlwaysFailure",
    "bt_sleep": "thymio_bt.btcpp.runtime.scripted:Sleep",
}
