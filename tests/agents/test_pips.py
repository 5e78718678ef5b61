"""PIPS programs: units, atomic features on hand-built scenes, evaluation, the strict JSON loader,
the `pips` policy and the "NAME:PATH" registry names."""

import json
import math

import numpy as np
import pytest

from socialzoo.agents import check_policy_spec, make_policy, split_policy_spec
from socialzoo.agents.pips import (
    Atom,
    Compare,
    Junction,
    Op,
    PipsPolicy,
    Program,
    ProgramError,
    Transition,
    expr_unit,
    load_program,
    program_from_json,
    shipped_program_path,
)
from socialzoo.agents.pips_features import (
    FAR,
    METRE,
    METRE_PER_SECOND,
    SECOND,
    Unit,
    UnitError,
    atom_spec,
    atom_values,
)
from socialzoo.nav.subpolicies import FOLLOW, GO_ALONE, HALT

K = 3


def observation(humans=(), target=(1.5, 0.0), goal=(10.0, 0.0), v=1.0, omega=0.0, prev=GO_ALONE):
    """One paper-layout observation; humans: (x, y, vx, vy) with vx, vy the human's own velocity
    in robot axes (the slot stores it relative to the robot)."""
    obs = np.zeros(7 + 4 * K, dtype=np.float32)
    obs[0:2], obs[2:4], obs[4:6], obs[6] = goal, target, (v, omega), prev
    for i, (x, y, vx, vy) in enumerate(humans):
        obs[7 + 4 * i : 11 + 4 * i] = (x, y, vx - v, vy)
    return obs


def test_units_multiply_divide_print_and_parse():
    assert METRE / METRE_PER_SECOND == SECOND
    assert str(METRE_PER_SECOND) == "m/s" and str(Unit()) == "1" and str(Unit(s=-1)) == "1/s"
    for unit in (METRE, SECOND, METRE_PER_SECOND, Unit(s=-1, rad=1), Unit(m=2), Unit(m=1, rad=-2), Unit()):
        assert Unit.parse(str(unit)) == unit
    for bad in ("kg", "m/s/s", "s*m", "", "m^0"):
        with pytest.raises(UnitError):
            Unit.parse(bad)


def test_expression_units_and_unit_errors():
    gap = Op("-", (Atom("lane60.dist"), Atom("target_dist")))
    assert expr_unit(gap) == METRE
    assert expr_unit(Op("/", (gap, Atom("robot_v")))) == SECOND
    with pytest.raises(UnitError, match=r"lane60.dist \[m\] and robot_v \[m/s\]"):
        expr_unit(Op("-", (Atom("lane60.dist"), Atom("robot_v"))))
    with pytest.raises(UnitError):
        Program({0: (Transition(HALT, Compare(Op("*", (gap, gap)), "<=", 1.0)),)})  # m^2 is not compared


def test_atomic_features_on_a_hand_built_scene():
    walker = (2.0, 0.3, 1.0, 0.0)  # ahead, 0.3 m to the left, walking our way at 1 m/s
    crosser = (1.0, -0.8, 0.0, 1.2)  # nearer, outside the 0.6 m lane, crossing
    behind = (-0.5, 0.0, 0.0, 0.0)  # nearest of all, behind, standing
    obs = np.stack([observation([behind, crosser, walker]), observation([])])
    names = ["near.dist", "ahead.dist", "lane60.dist", "lane60.absy", "lane60.speed", "lane60.mismatch"]
    names += ["lane25.dist", "ahead.closing", "near.mismatch", "target_dist", "num_visible", "num_ahead"]
    v = atom_values(obs, names)
    assert v["near.dist"][0] == pytest.approx(0.5)
    assert v["ahead.dist"][0] == pytest.approx(math.hypot(1.0, 0.8), rel=1e-6)
    assert v["lane60.dist"][0] == pytest.approx(math.hypot(2.0, 0.3), rel=1e-6)
    assert v["lane60.absy"][0] == pytest.approx(0.3, rel=1e-6)
    assert v["lane60.speed"][0] == pytest.approx(1.0, rel=1e-6)
    assert v["lane60.mismatch"][0] == pytest.approx(0.0, abs=1e-6)
    assert v["lane25.dist"][0] == FAR  # no one within 0.25 m of the heading line
    # The crosser moves (0, 1.2) while the robot moves (1, 0): relative (-1, 1.2) seen at (1, -0.8).
    assert v["ahead.closing"][0] == pytest.approx((1.0 * 1.0 + 0.8 * 1.2) / math.hypot(1.0, 0.8), rel=1e-5)
    assert v["near.mismatch"][0] == pytest.approx(math.pi)  # standing: no walking direction
    assert v["target_dist"][0] == pytest.approx(1.5)
    assert (v["num_visible"][0], v["num_ahead"][0]) == (3, 2)
    assert v["near.dist"][1] == FAR and v["lane60.speed"][1] == 0.0 and v["num_visible"][1] == 0
    with pytest.raises(KeyError, match=r"lane7\.dist"):
        atom_values(obs, ["lane7.dist"])
    assert atom_spec("lane62.x").unit == METRE


def two_rule_program():
    """GoAlone -> Halt when someone is in the 0.62 m lane within |target| + 0.9 m; back when clear;
    GoAlone -> Follow first if that someone walks our way."""
    gap = Op("-", (Atom("lane62.dist"), Atom("target_dist")))
    blocked = Compare(gap, "<=", 0.9)
    walking_our_way = Compare(Atom("lane62.mismatch"), "<=", 0.8)
    return Program(
        {
            GO_ALONE: (
                Transition(FOLLOW, Junction("and", (blocked, walking_our_way))),
                Transition(HALT, blocked),
            ),
            HALT: (Transition(GO_ALONE, Compare(gap, ">=", 1.2)),),
        }
    )


def random_observations(rng, n, k=K):
    obs = np.zeros((n, 7 + 4 * k), dtype=np.float32)
    obs[:, 0:4] = rng.uniform(-5, 5, (n, 4))
    obs[:, 4] = rng.uniform(0, 1.5, n)
    obs[:, 6] = rng.integers(0, 4, n)
    present = rng.random((n, k)) < 0.7
    slots = np.concatenate([rng.uniform(-1, 4, (n, k, 1)), rng.uniform(-1.5, 1.5, (n, k, 3))], axis=2)
    obs[:, 7:] = np.where(present[..., None], slots, 0.0).reshape(n, -1)
    return obs


def test_program_decides_batched_first_guard_wins():
    program = two_rule_program()
    walker_in_lane = (1.5, 0.2, 1.0, 0.0)
    crosser_in_lane = (1.5, 0.2, 0.0, 1.0)
    obs = np.stack(
        [
            observation([walker_in_lane], prev=GO_ALONE),
            observation([crosser_in_lane], prev=GO_ALONE),
            observation([], prev=GO_ALONE),
            observation([crosser_in_lane], prev=HALT),
            observation([(3.0, 0.2, 0.0, 1.0)], prev=HALT),  # 3.0 - 1.5 >= 1.2: clear
            observation([crosser_in_lane], prev=FOLLOW),  # no transitions out of Follow
        ]
    )
    assert program.decide(obs).tolist() == [FOLLOW, HALT, GO_ALONE, HALT, GO_ALONE, FOLLOW]
    policy = PipsPolicy(program)
    batch = random_observations(np.random.default_rng(0), 60)
    expected = np.array([program.decide(row[None])[0] for row in batch])
    assert np.array_equal(policy.act(batch), expected)
    assert np.array_equal(policy.act(batch.reshape(20, 3, -1)), expected.reshape(20, 3))
    assert policy.act(batch).dtype == np.int64


def test_save_load_gives_identical_actions(tmp_path):
    program = two_rule_program()
    path = program.save(tmp_path / "p.json")
    loaded = PipsPolicy.load(path)
    assert loaded.program == program
    batch = random_observations(np.random.default_rng(1), 500)
    assert np.array_equal(loaded.act(batch), PipsPolicy(program).act(batch))
    assert json.loads(path.read_text()) == loaded.config()
    assert any("-> Halt if (lane62.dist - target_dist) <= 0.9 m" in line for line in loaded.rules())


def broken(mutate):
    data = two_rule_program().to_json()
    mutate(data)
    return data


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda d: d["states"]["Halt"][0]["if"]["expr"].update(op="pow"), "unknown operator 'pow'"),
        (
            lambda d: d["states"]["Halt"][0]["if"]["expr"]["args"][0].update(feature="__import__('os')"),
            "unknown PIPS feature \"__import__\\('os'\\)\"",
        ),
        (lambda d: d["states"]["Halt"][0]["if"].update(cmp="<"), "unknown comparison '<'"),
        (lambda d: d["states"]["Halt"][0]["if"].update(unit="m/s"), "unit 'm/s' does not match"),
        (lambda d: d["states"]["Halt"][0]["if"].update(code="x"), r"unknown field\(s\) \['code'\]"),
        (lambda d: d["states"]["GoAlone"][0]["if"].update(op="xor"), "unknown junction 'xor'"),
        (lambda d: d["states"]["Halt"][0].update(to="Dance"), "unknown action 'Dance'"),
        (lambda d: d.update(format="pickle"), "format 'pickle'"),
        (lambda d: d.update(extra=1), r"unknown field\(s\) \['extra'\]"),
        (lambda d: d["states"]["Halt"][0]["if"].update(threshold=float("nan")), "finite number"),
        (
            lambda d: d["states"]["Halt"][0]["if"]["expr"].update(
                args=[{"feature": "lane62.dist"}, {"feature": "robot_v"}]
            ),
            r"\[m\] and robot_v \[m/s\]: the units differ",
        ),
    ],
)
def test_loader_refuses_unknown_operators_features_and_fields(tmp_path, mutate, message):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(broken(mutate)))
    with pytest.raises((ProgramError, UnitError), match=message) as info:
        load_program(path)
    assert str(path) in str(info.value)


def test_loader_names_where_the_bad_node_is():
    with pytest.raises(ProgramError, match=r"p\.states\.Halt\[0\]\.if\.expr: unknown operator"):
        program_from_json(broken(lambda d: d["states"]["Halt"][0]["if"]["expr"].update(op="eval")), "p")


def test_registry_names_with_a_file(tmp_path):
    path = two_rule_program().save(tmp_path / "Prog.json")
    policy = make_policy(f"PIPS:{path}")
    assert isinstance(policy, PipsPolicy) and policy.program == two_rule_program()
    assert split_policy_spec(f"Pips:{path}") == ("pips", str(path))
    check_policy_spec(f"pips:{path}")
    with pytest.raises(ValueError, match="no such file"):
        check_policy_spec(f"pips:{tmp_path / 'missing.json'}")
    with pytest.raises(ValueError, match="'ref' is not loaded from a file"):
        check_policy_spec(f"ref:{path}")
    with pytest.raises(ValueError, match="unknown policy 'robocop'"):
        check_policy_spec("robocop:x")
    with pytest.raises(ValueError, match="keyword arguments"):
        make_policy(f"pips:{path}", path=path)


def test_shipped_program_loads_and_acts():
    assert shipped_program_path().is_file()
    policy = make_policy("pips")
    assert isinstance(policy, PipsPolicy) and policy.program.transitions
    actions = policy.act(random_observations(np.random.default_rng(2), 100, k=25))
    assert set(actions.tolist()) <= {0, 1, 2, 3}
