#!/usr/bin/env python3
"""Which OpenSCENARIO files fall under issue 24's percentage goal, and why the others do not.

The issue asks that ">= 90 % run" of esmini's resources/xosc examples "whose roads netconvert
reads and whose actions and conditions are in the list above". This script decides the second
half of that sentence from the file itself (and, for a ParameterValueDistribution, from the
template it names), independently of vsd-sumo's reader, so the survey's denominator does not
depend on what vsd-sumo happens to support:

- actions: every element named *Action that is not a container of other actions must be one
  of the issue's list (TeleportAction, SpeedAction, LaneChangeAction, LaneOffsetAction,
  ActivateControllerAction, AssignControllerAction);
- conditions: every element named *Condition that is not a container must be one of its list;
- the file must name a road (RoadNetwork/LogicFile), whose path it prints for the survey to
  give to netconvert (the first half of the sentence).

usage: tools/xosc_scope.py FILE.xosc
prints one line: "in scope ROAD_PATH" or "outside: <what>"; exit 0 either way, 1 on unreadable
input.
"""
import os
import sys
import xml.etree.ElementTree as ElementTree

ISSUE_ACTIONS = {"TeleportAction", "SpeedAction", "LaneChangeAction", "LaneOffsetAction",
                 "ActivateControllerAction", "AssignControllerAction"}
ISSUE_CONDITIONS = {"SimulationTimeCondition", "StoryboardElementStateCondition", "ParameterCondition",
                    "RelativeDistanceCondition", "DistanceCondition", "TimeHeadwayCondition",
                    "TimeToCollisionCondition", "SpeedCondition", "RelativeSpeedCondition",
                    "AccelerationCondition", "ReachPositionCondition", "TraveledDistanceCondition",
                    "EndOfRoadCondition"}
# Elements whose names end in Action / Condition but that only hold another action or
# condition (OpenSCENARIO 1.0-1.2). EnvironmentAction is not among them: it holds an
# <Environment>, so it is an action of its own.
ACTION_CONTAINERS = {"Action", "PrivateAction", "GlobalAction", "UserDefinedAction", "LongitudinalAction",
                     "LateralAction", "ControllerAction", "RoutingAction", "EntityAction", "ParameterAction",
                     "InfrastructureAction", "TrafficSignalAction", "TrafficAction", "AppearanceAction",
                     "TrailerAction", "VariableAction"}
CONDITION_CONTAINERS = {"Condition", "ByEntityCondition", "ByValueCondition", "EntityCondition"}


def local_name(tag):
    return tag.rsplit("}", 1)[-1]


def scenario_of(path):
    """The scenario file's root: the file itself, or the template a distribution names."""
    root = ElementTree.parse(path).getroot()
    distribution = root.find(".//ParameterValueDistribution/ScenarioFile")
    if distribution is not None:
        template = os.path.join(os.path.dirname(path), distribution.get("filepath", ""))
        return template, ElementTree.parse(template).getroot()
    return path, root


def outside_the_issue(root):
    names = {local_name(element.tag) for element in root.iter()}
    actions = {n for n in names if n.endswith("Action") and n not in ACTION_CONTAINERS}
    conditions = {n for n in names if n.endswith("Condition") and n not in CONDITION_CONTAINERS}
    return sorted(actions - ISSUE_ACTIONS) + sorted(conditions - ISSUE_CONDITIONS)


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: tools/xosc_scope.py FILE.xosc")
    try:
        path, root = scenario_of(sys.argv[1])
    except (OSError, ElementTree.ParseError) as error:
        sys.exit(f"xosc_scope.py: {sys.argv[1]}: {error}")
    outside = outside_the_issue(root)
    logic = root.find(".//RoadNetwork/LogicFile")
    if logic is None:
        outside.append("no road (RoadNetwork/LogicFile)")
    if outside:
        print("outside: " + ", ".join(outside))
    else:
        print("in scope " + os.path.normpath(os.path.join(os.path.dirname(path), logic.get("filepath", ""))))


if __name__ == "__main__":
    main()
