"""The suite's scenario cards: every shipped card loads and agrees with the suite, and a malformed
card is a CardError naming the file and the field."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import jsonschema
import pytest

from socialzoo.core.metrics import names as metric_names
from socialzoo.scenarios import cards
from socialzoo.scenarios.cards import CardError, card_path, load_card, suite_cards
from socialzoo.scenarios.catalogue import FAMILIES, get_family
from socialzoo.scenarios.suite import SUITE, SUITE_NAMES, SUITE_SPLITS

CARD_DIR = Path(cards.__file__).parent / "cards"


def test_every_shipped_card_loads_in_suite_order():
    loaded = suite_cards()
    assert [(c.letter, c.family, c.title) for c in loaded] == [tuple(e) for e in SUITE]
    for card in loaded:
        assert Path(card.path) == CARD_DIR / f"{card.family}.toml"
        assert dict(card.seeds) == SUITE_SPLITS
        assert card.version >= 1 and "Francis et al. 2025" in card.source and "socialzoo" in card.source
        assert card.people and card.success and card.variation and card.limitations
        assert set(card.metrics) <= set(metric_names())
        assert card.robot.goal_kind in ("reach", "follow", "lead", "accompany", "join")


def test_the_cards_folder_holds_one_card_per_suite_scenario():
    assert sorted(p.stem for p in CARD_DIR.glob("*.toml")) == sorted(SUITE_NAMES)
    assert sorted(p.name for p in CARD_DIR.iterdir() if p.suffix != ".toml") == []


def test_a_card_is_found_by_family_or_letter():
    assert load_card("i") == load_card("blind_corner") == load_card(CARD_DIR / "blind_corner.toml")
    assert load_card(str(CARD_DIR / "blind_corner.toml")).letter == "i"
    with pytest.raises(CardError, match="not a suite scenario"):
        load_card("crossing")


def test_the_schema_is_a_valid_draft_2020_12_schema():
    jsonschema.Draft202012Validator.check_schema(cards.schema())


def test_registered_suite_families_play_on_their_card_map():
    """Once a suite family is registered, its card must name the map it is designed for."""
    for card in suite_cards():
        if card.family not in FAMILIES:
            continue
        try:
            family = get_family(card.family)
        except (ImportError, AttributeError):  # named in the registry, its class not written yet
            continue
        assert family.map_name == card.map_name, card.family


def test_the_success_criteria_give_the_suite_ids_goal_radius_and_time_limit():
    """The cards are shown beside the suite's results: their goal radius and time limit must be those
    of the ids the suite plays (socialzoo/Suite-v3, socialzoo/CrowdNavSuite-v2), not EnvConfig's defaults."""
    import gymnasium as gym

    import socialzoo  # noqa: F401  (registers the ids)
    from socialzoo.env.registration import SUITE_IDS

    suite_as, suite_cn = (gym.make(env_id).unwrapped.task for env_id in SUITE_IDS)
    limits = {suite_as.config.max_steps * suite_as.core.world.dt, suite_cn.config.time_limit}
    assert len(limits) == 1
    words = (
        f"{suite_as.config.goal_radius:g} m in socialzoo/Suite-v3",
        f"the robot's radius, {suite_cn.core.world.robot.radius:g} m, in socialzoo/CrowdNavSuite-v2",
        f"before the time limit ({limits.pop():g} s in both)",
    )
    for card in suite_cards():
        assert any(all(w in line for w in words) for line in card.success), (card.family, card.success)


def test_the_module_imports_no_numpy():
    tree = ast.parse(Path(cards.__file__).read_text())
    top = [n for n in tree.body if isinstance(n, (ast.Import, ast.ImportFrom))]
    imported = {a.name for n in top if isinstance(n, ast.Import) for a in n.names}
    imported |= {n.module or "" for n in top if isinstance(n, ast.ImportFrom)}
    assert not any(name.split(".")[0] == "numpy" for name in imported)


def _sub(pattern: str, replacement: str, count: int = 1):
    def edit(text: str) -> str:
        new, n = re.subn(pattern, replacement, text, count=count, flags=re.MULTILINE)
        assert n, f"pattern {pattern!r} is not in the card"
        return new

    return edit


# (name, edit of blind_corner.toml's text, the field the error names, words of its problem)
MALFORMED = [
    ("missing field", _sub(r'^map = "corner"\n', ""), "definition.map", "missing"),
    ("missing table", _sub(r"^\[usage\]\n(.|\n)*", ""), "usage", "missing"),
    ("missing nested field", _sub(r'^goal_kind = "reach"\n', ""), "definition.robot.goal_kind", "missing"),
    ("missing role field", _sub(r"^count = \[1, 1\]\n", ""), "definition.people[0].count", "missing"),
    ("wrong type", _sub(r"^count = \[1, 1\]", 'count = "one"'), "definition.people[0].count", "array"),
    (
        "wrong item type",
        _sub(r"^speed = \[0.5, 1.3\]", 'speed = [0.5, "fast"]'),
        "definition.people[0].speed[1]",
        "number",
    ),
    ("wrong version type", _sub(r"^version = 1", 'version = "1"'), "metadata.version", "integer"),
    ("unknown field", _sub(r"^version = 1", "version = 1\nauthor = 'me'"), "metadata", "author"),
    (
        "bad goal kind",
        _sub(r'^goal_kind = "reach"', 'goal_kind = "wander"'),
        "definition.robot.goal_kind",
        "wander",
    ),
    (
        "letter",
        _sub(r'^letter = "i"', 'letter = "j"'),
        "metadata.letter",
        "the suite gives blind_corner letter 'i'",
    ),
    ("title", _sub(r'^title = "Blind corner"', 'title = "Corner"'), "metadata.title", "Blind corner"),
    (
        "speed order",
        _sub(r"^speed = \[0.5, 1.3\]", "speed = [1.3, 0.5]"),
        "definition.people[0].speed",
        "least",
    ),
    (
        "range order",
        _sub(r"^range = \[0.5, 1.3\]", "range = [1.3, 0.5]"),
        "definition.variation[0].range",
        "least",
    ),
    ("range without unit", _sub(r'^unit = "m/s"\n', ""), "definition.variation[0]", "'unit' is a dependency"),
    (
        "range and values",
        _sub(r'^unit = "m/s"\n', 'unit = "m/s"\nvalues = ["slow", "fast"]\n'),
        "definition.variation[0]",
        "exactly one of: range or values",
    ),
    (
        "neither range nor values",
        _sub(r'^range = \[0.5, 1.3\]\nunit = "m/s"\n', ""),
        "definition.variation[0]",
        "exactly one of: range or values",
    ),
    (
        "unknown metric",
        _sub(r'"gl_jerk_max"', '"jerkiness"'),
        "usage.metrics[5]",
        "'jerkiness' is not a registered metric",
    ),
    (
        "seed split",
        _sub(r"^test = \{ first = 100, size = 500 \}", "test = { first = 100, size = 400 }"),
        "definition.seeds.test",
        "suite",
    ),
    (
        "no limitations",
        _sub(r"^limitations = \[\n(.|\n)*?^\]", "limitations = []"),
        "usage.limitations",
        "non-empty",
    ),
]


@pytest.mark.parametrize(
    ("edit", "field", "problem"), [m[1:] for m in MALFORMED], ids=[m[0] for m in MALFORMED]
)
def test_a_malformed_card_names_the_file_and_the_field(tmp_path, edit, field, problem):
    path = tmp_path / "blind_corner.toml"
    path.write_text(edit((CARD_DIR / "blind_corner.toml").read_text()))
    with pytest.raises(CardError) as caught:
        load_card(path)
    err = caught.value
    assert (err.source, err.field) == (str(path), field), str(err)
    assert problem in err.problem, str(err)
    assert str(err).startswith(f"{path}: {field}: ")


def test_an_unknown_family_is_named(tmp_path):
    path = tmp_path / "blind_alley.toml"
    path.write_text((CARD_DIR / "blind_corner.toml").read_text().replace('"blind_corner"', '"blind_alley"'))
    with pytest.raises(CardError, match=r"blind_alley.toml: metadata.family: unknown family 'blind_alley'"):
        load_card(path)


def test_the_family_must_be_the_file_name(tmp_path):
    path = tmp_path / "corner.toml"
    path.write_text((CARD_DIR / "blind_corner.toml").read_text())
    with pytest.raises(
        CardError, match=r"corner.toml: metadata.family: 'blind_corner' must be the file's name"
    ):
        load_card(path)


def test_a_file_that_is_not_toml_or_missing_is_named(tmp_path):
    path = tmp_path / "blind_corner.toml"
    path.write_text("[metadata\nletter = 'i'\n")
    with pytest.raises(CardError, match=r"blind_corner.toml: \(file\): is not TOML"):
        load_card(path)
    with pytest.raises(CardError, match=r"nowhere.toml: \(file\): cannot be read"):
        load_card(tmp_path / "nowhere.toml")


def test_card_path_names_the_shipped_file():
    assert card_path("a") == CARD_DIR / "frontal_approach.toml"
    with pytest.raises(CardError, match=r"nope: \(name\): not a suite scenario"):
        card_path("nope")
