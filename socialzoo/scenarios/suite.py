"""The field's scenario suite: the 25 scenarios of Fig. 7 of Francis et al., "Principles and Guidelines for Evaluating
Social Robot Navigation Algorithms" (ACM THRI 2025, arXiv 2306.16740), each a registered scenario family."""

from __future__ import annotations

from typing import NamedTuple

from socialzoo.scenarios.catalogue import SeedSplit

# Every suite family's seeds: validation cases 0-99, test cases 100-599, training from 1000 up
# (a training stream skips any seed below it), so no test case is ever a training case.
SUITE_SPLITS = {
    "val": SeedSplit(0, 100),
    "test": SeedSplit(100, 500),
    "train": SeedSplit(1000, None),
}


class SuiteEntry(NamedTuple):
    """One scenario of the suite: its letter in Fig. 7, its family's registry name, its title.

    Each entry is a registered scenario family (socialzoo.scenarios.catalogue), with the suite's seed
    splits (SUITE_SPLITS) and its scenario card (socialzoo.scenarios.cards).
    """

    letter: str
    family: str
    title: str


SUITE: tuple[SuiteEntry, ...] = (
    SuiteEntry("a", "frontal_approach", "Frontal approach"),
    SuiteEntry("b", "pedestrian_obstruction", "Pedestrian obstruction"),
    SuiteEntry("c", "pedestrian_overtaking", "Pedestrian overtaking"),
    SuiteEntry("d", "robot_overtaking", "Robot overtaking"),
    SuiteEntry("e", "down_path", "Down path"),
    SuiteEntry("f", "intersection_no_gesture", "Intersection, no gesture"),
    SuiteEntry("g", "intersection_wait", "Intersection with a wait gesture"),
    SuiteEntry("h", "intersection_proceed", "Intersection with a proceed gesture"),
    SuiteEntry("i", "blind_corner", "Blind corner"),
    SuiteEntry("j", "narrow_hallway", "Narrow hallway"),
    SuiteEntry("k", "narrow_doorway", "Narrow doorway"),
    SuiteEntry("l", "entering_room", "Entering a room"),
    SuiteEntry("m", "exiting_room", "Exiting a room"),
    SuiteEntry("n", "entering_elevator", "Entering an elevator"),
    SuiteEntry("o", "exiting_elevator", "Exiting an elevator"),
    SuiteEntry("p", "joining_group", "Joining a group"),
    SuiteEntry("q", "leaving_group", "Leaving a group"),
    SuiteEntry("r", "following_person", "Following a person"),
    SuiteEntry("s", "leading_person", "Leading a person"),
    SuiteEntry("t", "accompanying_peer", "Accompanying a peer"),
    SuiteEntry("u", "crowd_navigation", "Crowd navigation"),
    SuiteEntry("v", "parallel_flow", "Parallel traffic"),
    SuiteEntry("w", "perpendicular_flow", "Perpendicular traffic"),
    SuiteEntry("x", "circular_crossing", "Circular crossing"),
    SuiteEntry("y", "robot_crowding", "Robot crowding"),
)

SUITE_NAMES: tuple[str, ...] = tuple(entry.family for entry in SUITE)


def suite_entry(name_or_letter: str) -> SuiteEntry:
    """The suite's entry for a family name or a Fig. 7 letter.

    Raises:
        KeyError: neither (the message lists the suite's names).
    """
    for entry in SUITE:
        if name_or_letter in (entry.family, entry.letter):
            return entry
    raise KeyError(f"unknown suite scenario {name_or_letter!r}; known: {', '.join(SUITE_NAMES)}")
