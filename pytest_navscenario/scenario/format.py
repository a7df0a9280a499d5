"""The whole scenario format (version 1): the top-level keys and the sections below them, as
declared in ``keys.py`` form next to their dataclasses. The loader, the JSON Schema, the reference
page and the search read ``SCENARIO``.

A new top-level section is one ``Sub``/``Elements`` key in ``SCENARIO`` (and a field of
``Scenario``); a new element type of a typed list is one ``Element`` in its ``Elements`` key.
"""
from __future__ import annotations

from .keys import REQUIRED, Free, Marks, Rule, Section, Sub, Text, Version, section, walk
from .model import MISSION, OBSTACLES, REFERENCE, ROBOT, SCHEMA_VERSION, SIMULATION, Scenario
from .requirements import REQUIREMENTS, SIGNALS
from .search_keys import SEARCH
from .terrain import TERRAIN

SUPPORTED_VERSIONS = (SCHEMA_VERSION,)

SCENARIO = section(Scenario, "", "a navigation test case: robot, mission, obstacles and simulation settings", [
    Version("version", "", "the format version; this release reads version 1", versions=SUPPORTED_VERSIONS,
            default=REQUIRED, example=f"version: {SCHEMA_VERSION}"),
    Text("name", "", "the test item's name; one line, no '/' or '\\' (it names files)", name_rules=True,
         file_name=True, default_doc="the file name without .yaml"),
    Text("family", "", "groups scenarios in reports and comparisons: a name or a relative folder path "
         "such as examples/scenarios", nonempty=False, name_rules=True, default_doc="the folder's name"),
    Text("description", "", "free text", nonempty=False),
    Marks("marks", "", "pytest marks: name, {name: {kw: value}}, {name: [a, b]} or {name: value}"),
    Sub("robot", "", "the robot: outline, drive, limits, lidar, safety layer, faults", section=ROBOT),
    Sub("mission", "", "start, goal, waypoints, tolerances and timeout", section=MISSION, default=REQUIRED,
        nullable=False, example="mission: {start: {x: 0, y: 0}, goal: {x: 0, y: 10}}"),
    OBSTACLES,
    TERRAIN,
    Sub("simulation", "", "physics step, control rate and noise seed", section=SIMULATION),
    Sub("reference", "", "a recorded trajectory to compare the run with", section=REFERENCE, default=None),
    SIGNALS,
    REQUIREMENTS,
    Sub("search", "", "the failure search's space around this seed (see the failure search)", section=SEARCH,
        default=None),
    Free("provenance", "", "written by the search: where a frozen failure came from", default=None),
], what="a mapping of scenario fields", rules=[
    Rule("names are unique across obstacles and terrain elements", None),
    Rule("1 / (timestep × control_rate) is a whole number of physics steps, and timeout / timestep at most "
         "10⁷ steps", None),
    Rule("latencies are whole multiples of the control period and shorter than the timeout", None),
    Rule("the robot's footprint at the start and the goal, and each waypoint, are clear of obstacles (a moving "
         "obstacle where it stands at t = 0, and it may cross the goal and the waypoints)", None),
    Rule("the body goes with the drive (a wheeled body cannot drive omni) and with the terrain (the planar "
         "body cannot ride it); start and goal stand on the ground (not over a pit or stairwell, not half "
         "on a platform), and no waypoint lies over a hole", None),
    Rule("an obstacle's z stands it on the ground under it, neither floating above it nor buried under it "
         "(the planar body's obstacles stand on its flat floor: z 0 or left out)", None),
    Rule("the terrain has at most 5000 blocks (each step of a flight counts) and at most 100 elements "
         "cutting holes in the floor", None),
    Rule("free-form data (provenance, mark arguments) holds only text, numbers, true/false, null, lists and "
         "mappings: a YAML date must be quoted", None),
])


def key_homes(root: Section = SCENARIO) -> tuple[tuple[str, tuple[str, ...]], ...]:
    """(where, keys) of every section whose keys are suggested when written elsewhere ("'beams'
    belongs under 'robot.lidar'"); the element types of one list are merged."""
    homes: dict[str, list[str]] = {}
    for path, sec in walk(root):
        if sec.home:
            names = homes.setdefault(path, [])
            names.extend(n for n in sec.names if n not in names)
    return tuple((path, tuple(names)) for path, names in homes.items())
