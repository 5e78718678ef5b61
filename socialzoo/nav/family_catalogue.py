"""The scenario families by name: the small map each is designed for, and what happens in it.

Free of numpy, so that the Gymnasium registration (socialzoo.env.registration) names every
family's id without importing the world; socialzoo.nav.scenario_families gives each its layout.
"""

from __future__ import annotations

# Family name -> (the small map it is designed for, one line saying what happens).
FAMILY_CATALOGUE: dict[str, tuple[str, str]] = {
    "hallway_head_on": ("hallway", "1-3 humans walk down the hallway towards the robot"),
    "overtaking": ("hallway", "a slow human (0.4-0.6 m/s) walks ahead of the robot, same way"),
    "crossing": ("intersection", "2-4 humans cross the robot's way along the other corridor"),
    "doorway": ("doorway", "1-3 humans come through the door the robot must pass"),
    "circle_crossing": ("open_room", "robot and 4-8 humans on a circle walk to the antipode"),
    "parallel_traffic": ("hallway", "4-8 humans walk the robot's way at mixed speeds"),
}
