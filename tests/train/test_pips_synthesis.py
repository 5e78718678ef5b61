"""PIPS synthesis: unit-consistent enumeration, exact threshold search against z3 and brute force,
windowing, recovery of a known program, train()'s files, and agreement with Ref."""

import dataclasses
import itertools
import json

import numpy as np
import pytest

from socialzoo.agents.demonstrations import DemonstrationError
from socialzoo.agents.pips import (
    SAME_UNIT_OPS,
    Atom,
    Compare,
    Junction,
    Op,
    PipsPolicy,
    Program,
    Transition,
    expr_unit,
    load_program,
)
from socialzoo.agents.pips_features import (
    ATOMS,
    COMPARABLE_UNITS,
    FAR,
    METRE,
    METRE_PER_SECOND,
    paper_parts,
)
from socialzoo.nav.subpolicies import GO_ALONE, HALT
from socialzoo.train.pips import (
    PipsArgs,
    episode_order,
    oscillations,
    read_program_record,
    synthesize,
    train,
    window_mask,
    without_dead_ends,
)
from socialzoo.train.pips_enumerate import combine, enumerate_depth
from socialzoo.train.pips_search import SearchSettings, physical_thresholds
from socialzoo.train.pips_thresholds import PairSearch, fit_single, solve_z3
from socialzoo.train.run_dir import RunDirError

pytest.importorskip("z3")


def walk(expr):
    yield expr
    if isinstance(expr, Op):
        for a in expr.args:
            yield from walk(a)


def test_enumeration_never_mixes_metres_with_metres_per_second():
    atoms = [Atom(n) for n in ATOMS]
    depth1 = enumerate_depth(1, atoms, atoms)
    depth2 = enumerate_depth(2, depth1[::40], atoms)
    assert len(depth1) > 1000 and len(depth2) > 100
    for expr in depth1 + depth2:
        assert expr_unit(expr) in COMPARABLE_UNITS
        for node in walk(expr):
            if isinstance(node, Op) and node.op in SAME_UNIT_OPS:
                assert expr_unit(node.args[0]) == expr_unit(node.args[1]), node
    # Metres and metres per second meet only in a ratio (a time), never in a sum or difference.
    dist, speed = Atom("lane60.dist"), Atom("robot_v")
    assert expr_unit(dist) == METRE and expr_unit(speed) == METRE_PER_SECOND
    mixed = combine(dist, speed)
    assert {e.op for e in mixed} == {"/"} and all(expr_unit(e) in COMPARABLE_UNITS for e in mixed)
    assert not any(
        isinstance(e, Op)
        and e.op in SAME_UNIT_OPS
        and {expr_unit(e.args[0]), expr_unit(e.args[1])} == {METRE, METRE_PER_SECOND}
        for x in depth1 + depth2
        for e in walk(x)
    )


def brute_force(columns, label, junction, cmps):
    best = -1
    # Every threshold that matters: at each value, and beyond both ends (a side always or never true).
    grid = [np.concatenate([np.unique(c), [c.min() - 1, c.max() + 1]]) for c in columns]
    for ts in itertools.product(*grid):
        holds = [c <= t if cmp == "<=" else c >= t for c, t, cmp in zip(columns, ts, cmps, strict=True)]
        guard = holds[0]
        for h in holds[1:]:
            guard = guard & h if junction == "and" else guard | h
        best = max(best, int((guard == label).sum()))
    return best


def test_exact_threshold_search_finds_the_z3_optimum():
    """On small random cases the exact search's optimum equals z3's MaxSMT optimum and brute force,
    for single comparisons and for pairs (both junctions, all directions)."""
    rng = np.random.default_rng(0)
    for _ in range(12):
        n = int(rng.integers(12, 30))
        x = np.round(rng.normal(size=(2, n)), 1)
        label = (x[0] + 0.5 * x[1] + rng.normal(scale=0.5, size=n)) < 0.2
        weight = np.ones(n)
        single = fit_single(x[:1], label, weight)
        z3_single = solve_z3(("leaf", 0, str(single.cmp[0])), [x[0]], label, weight)
        assert z3_single is not None and z3_single[0] == single.score[0]
        assert single.score[0] == max(brute_force([x[0]], label, "and", [c]) for c in ("<=", ">="))
        pair = PairSearch(x[1:], label, weight).fit(x[0])
        singles = fit_single(x, label, weight).score
        # The search's optimum over both features: a pair, either one alone, or a constant guard.
        exact = max(pair.score[0], *singles, label.sum(), (~label).sum())
        best_z3 = 0.0
        for junction, ca, cb in itertools.product(("and", "or"), ("<=", ">="), ("<=", ">=")):
            solved = solve_z3((junction, [("leaf", 0, ca), ("leaf", 1, cb)]), [x[0], x[1]], label, weight)
            assert solved is not None
            assert solved[0] == brute_force([x[0], x[1]], label, junction, [ca, cb])
            best_z3 = max(best_z3, solved[0])
        assert exact == best_z3


def test_window_mask_keeps_steps_near_changes_in_the_same_episode():
    action = np.array([0, 0, 0, 1, 1, 1, 1, 0, 0, 0])
    prev = np.array([0, 0, 0, 0, 1, 1, 1, 1, 0, 0])
    episode = np.array([0, 0, 0, 0, 0, 0, 1, 1, 1, 1])
    assert window_mask(action, prev, episode, 1).tolist() == [0, 0, 1, 1, 1, 0, 1, 1, 1, 0]
    assert window_mask(action, prev, episode, 0).all()


# A known two-transition program: halt when the lane ahead is blocked within |target| + 0.7 m,
# go again once the human in the lane is 3 m away.
GAP = Op("-", (Atom("lane50.dist"), Atom("target_dist")))
KNOWN = Program(
    {
        GO_ALONE: (Transition(HALT, Compare(GAP, "<=", 0.7)),),
        HALT: (Transition(GO_ALONE, Compare(Atom("lane50.dist"), ">=", 3.0)),),
    }
)


def synthetic_episodes(rng, program, episodes, steps=240, k=3):
    """Observations of a human walking to and fro in the lane ahead, with a bystander beside the
    lane and one behind; the previous action follows `program` (the demonstrator)."""
    obs_list, act_list, ep_list = [], [], []
    t = np.arange(steps)
    for e in range(episodes):
        obs = np.zeros((steps, 7 + 4 * k), dtype=np.float32)
        bearing, reach = rng.uniform(-0.4, 0.4), rng.uniform(1.2, 1.8)
        obs[:, 0:2] = (8.0, rng.uniform(-3, 3))
        obs[:, 2:4] = reach * np.cos(bearing), reach * np.sin(bearing)
        obs[:, 4] = rng.uniform(0.2, 1.5, steps)
        x = 4.0 + 3.2 * np.cos(2 * np.pi * t / rng.uniform(120, 200) + rng.uniform(0, 2 * np.pi))
        humans = [
            np.stack([x, rng.uniform(-0.3, 0.3) + 0.0 * t, np.gradient(x) * 40, 0.0 * t], axis=1),
            np.stack([rng.uniform(0.5, 6, steps), rng.choice([-1, 1]) * rng.uniform(0.8, 2, steps)], axis=1),
            np.stack([rng.uniform(-3, -0.3, steps), rng.uniform(-1, 1, steps)], axis=1),
        ]
        humans[1] = np.concatenate([humans[1], rng.uniform(-1, 1, (steps, 2))], axis=1)
        humans[2] = np.concatenate([humans[2], rng.uniform(-1, 1, (steps, 2))], axis=1)
        for i, h in enumerate(humans):
            obs[:, 7 + 4 * i : 11 + 4 * i] = h
        action = np.zeros(steps, dtype=np.int64)
        prev = GO_ALONE
        for s in range(steps):
            obs[s, 6] = prev
            prev = action[s] = program.decide(obs[s : s + 1])[0]
        obs_list.append(obs)
        act_list.append(action)
        ep_list.append(np.full(steps, e))
    return np.concatenate(obs_list), np.concatenate(act_list), np.concatenate(ep_list)


def test_recovers_a_known_two_transition_program():
    rng = np.random.default_rng(3)
    obs, action, episode = synthetic_episodes(rng, KNOWN, 16)
    mask = window_mask(action, obs[:, 6].astype(int), episode, 10)
    assert 20 <= (action != obs[:, 6]).sum() and mask.sum() < len(mask)
    settings = SearchSettings(max_depth=1, solver="z3")
    learned, reports = synthesize(obs[mask], action[mask], settings)
    assert sorted(learned.transitions) == [GO_ALONE, HALT]
    assert {r.solver for r in reports} == {"z3"}
    held_out, _, _ = synthetic_episodes(np.random.default_rng(4), KNOWN, 8)
    held_out[:, 6] = np.random.default_rng(5).integers(0, 2, len(held_out))  # both states everywhere
    agree = (learned.decide(held_out) == KNOWN.decide(held_out)).mean()
    assert agree >= 0.99
    for state, (true_t,) in KNOWN.transitions.items():
        (got,) = learned.transitions[state]
        assert got.target == true_t.target and isinstance(got.guard, Compare)
        assert got.guard.cmp == true_t.guard.cmp
        assert expr_unit(got.guard.expr) == METRE
        assert got.guard.threshold == pytest.approx(true_t.guard.threshold, abs=0.1)


def write_demos(path, obs, action, episode):
    lengths = np.bincount(episode)
    ids = np.flatnonzero(lengths)
    np.savez_compressed(
        path,
        obs=obs,
        action=action,
        next_obs=obs,
        reward=np.zeros(len(action), np.float32),
        terminated=np.zeros(len(action), bool),
        truncated=np.zeros(len(action), bool),
        episode=episode,
        episode_ids=ids,
        episode_seeds=ids.astype(np.uint64),
        episode_lengths=lengths[ids],
        metadata=np.array(json.dumps({"format": "socialzoo-demos/1", "config_hash": "synthetic"})),
    )


def test_train_writes_the_program_and_its_record(tmp_path):
    obs, action, episode = synthetic_episodes(np.random.default_rng(6), KNOWN, 12)
    demos = tmp_path / "demos.npz"
    write_demos(demos, obs, action, episode)
    args = PipsArgs(demos=str(demos), out=str(tmp_path / "p.json"), steps=2000, max_depth=1, solver="exact")
    out = train(args)
    record = read_program_record(out)
    assert record["args"]["steps"] == 2000 and record["seed"] == 0 and record["synthesis_seconds"] > 0
    assert record["command"] and record["rules"] == load_program(out).rules()
    assert record["demonstrations"]["steps_spanned"] == 2000
    assert record["agreement"]["held_out"]["steps"] == len(action) - 2000
    assert record["agreement"]["held_out"]["agreement"] > 0.98
    policy = PipsPolicy.load(out)
    assert np.array_equal(policy.act(obs), load_program(out).decide(obs))
    # Another program of other arguments under the same name is refused; the folder may hold any
    # number of programs, so the message named the folder ("tmp holds a pips run ... choose another
    # folder") where the file is what to change.
    with pytest.raises(RunDirError) as refused:
        train(dataclasses.replace(args, max_depth=2))
    message = str(refused.value)
    assert "max_depth differ" in message and "choose another --out" in message
    assert "choose another folder" not in message and f"{tmp_path} holds" not in message


def test_thresholds_only_the_absent_person_stand_in_reaches_are_refused():
    """Env v2's first program halted on "(ahead.absy - lane37.x) <= -999.4 m": with nobody in the
    0.37 m lane (read as FAR away) it fires on anyone 0.6 m to the side at any distance. Such a
    threshold lies outside the expression's values where its people are there."""
    present = np.array([True, True, False, False])
    atoms = {
        "ahead.dist": np.array([3.0, 5.0, 4.0, 6.0]),
        "ahead.absy": np.array([0.2, 0.5, 0.5, 1.0]),
        "lane37.dist": np.where(present, [3.0, 5.0, 0, 0], FAR),
        "lane37.x": np.where(present, [2.9, 4.9, 0, 0], FAR),
    }
    gap = Op("-", (Atom("ahead.absy"), Atom("lane37.x")))
    assert not physical_thresholds(Compare(gap, "<=", -999.4), atoms)
    assert physical_thresholds(Compare(gap, "<=", -3.0), atoms)  # among the present values
    # Either comparison of a junction can be the artefact.
    both = Junction("or", (Compare(Atom("ahead.absy"), "<=", 0.3), Compare(gap, "<=", -999.4)))
    assert not physical_thresholds(both, atoms)
    # An atomic feature compares with the stand-in as it reads: "nobody within 500 m of the lane".
    assert physical_thresholds(Compare(Atom("lane37.dist"), ">=", 500.0), atoms)
    # Features of the robot alone have no people to be absent.
    assert physical_thresholds(Compare(Op("-", (Atom("goal_dist"), Atom("target_dist"))), ">=", 1e4),
                               {"goal_dist": np.ones(4), "target_dist": np.ones(4)})  # fmt: skip


def test_no_transition_into_a_state_the_program_cannot_leave():
    """Env v2's seed-4 sample taught GoAlone -> Follow but no way out of Follow: the robot followed
    until the time limit. Only GoAlone, which drives to the goal, may have no way out."""
    FOLLOW = 2
    near = Compare(Atom("lane62.dist"), "<=", 2.4)
    far = Compare(Atom("lane62.dist"), ">=", 2.5)
    program = {
        GO_ALONE: (Transition(HALT, near), Transition(FOLLOW, near)),
        HALT: (Transition(GO_ALONE, far),),
    }
    assert without_dead_ends(program) == {
        GO_ALONE: (Transition(HALT, near),),
        HALT: (Transition(GO_ALONE, far),),
    }
    # Halt's only way out leads into a dead end: Halt becomes one, and the way into it goes too.
    chain = {GO_ALONE: (Transition(HALT, near),), HALT: (Transition(FOLLOW, far),)}
    assert without_dead_ends(chain) == {}
    assert without_dead_ends({HALT: (Transition(GO_ALONE, far),)}) == {HALT: (Transition(GO_ALONE, far),)}


def _ahead(dist, prev):
    """A paper-layout observation with one person straight ahead at `dist`, in state `prev`."""
    obs = np.zeros((len(dist), 7 + 4 * 3))
    obs[:, 0:2] = (8.0, 0.0)
    obs[:, 2:4] = (1.5, 0.0)
    obs[:, 4] = 1.0
    obs[:, 6] = prev
    obs[:, 7] = dist
    return obs


def test_a_program_that_would_halt_and_go_on_alternate_steps_is_learned_again():
    """The demonstrator halts for anyone within 3 m. The windowed examples leave a gap, so the
    guards come out as "halt within 3.25 m" and "go again beyond 2.5 m": between them the robot
    would flip every step (seeds 1 and 3 of env v2's samples did, on 13% and 7% of their steps).
    The sample's own steps in the gap, with the demonstrator's action from both states, close it."""
    go_alone = [(d, GO_ALONE, HALT) for d in np.linspace(0.5, 3.0, 12)] + [
        (d, GO_ALONE, GO_ALONE) for d in np.linspace(3.5, 8.0, 12)
    ]
    halted = [(d, HALT, HALT) for d in np.linspace(0.5, 1.5, 12)] + [
        (d, HALT, GO_ALONE) for d in np.linspace(3.5, 8.0, 12)
    ]
    rows = go_alone + halted
    obs = np.concatenate([_ahead(np.array([d]), prev) for d, prev, _ in rows])
    action = np.array([a for _, _, a in rows])
    gap = np.linspace(2.6, 3.0, 9)
    sample_obs = np.concatenate([obs, _ahead(gap, HALT)])
    sample_action = np.concatenate([action, np.full(len(gap), HALT)])
    settings = SearchSettings(max_depth=0, max_pred_size=1, solver="exact")
    plain, _ = synthesize(obs, action, settings)
    assert oscillations(plain, paper_parts(sample_obs))  # the gap: halt from GoAlone, go from Halt
    repaired, _ = synthesize(obs, action, settings, sample=(sample_obs, sample_action))
    assert oscillations(repaired, paper_parts(sample_obs)) == []
    # It still halts for the person within 3 m and goes again once they are farther than 3.5 m.
    assert repaired.decide(_ahead(np.array([2.8, 1.0]), GO_ALONE)).tolist() == [HALT, HALT]
    assert repaired.decide(_ahead(np.array([2.8, 4.0]), HALT)).tolist() == [HALT, GO_ALONE]


def test_a_seed_reads_whole_episodes_in_its_own_order():
    episode = np.array([7, 7, 7, 2, 2, 9, 9, 9, 9, 4])
    assert episode_order(episode, 0).tolist() == list(range(10))
    orders = {tuple(episode[episode_order(episode, seed)].tolist()) for seed in range(1, 6)}
    for order in orders:
        steps = np.asarray(order)
        runs = steps[np.r_[True, steps[1:] != steps[:-1]]]
        assert sorted(runs.tolist()) == [2, 4, 7, 9]  # each episode whole, once
    assert len(orders) > 1
    picked = episode_order(episode, 3)
    assert sorted(picked.tolist()) == list(range(10))
    for e in (7, 2, 9, 4):  # steps keep their order inside an episode
        inside = picked[episode[picked] == e]
        assert np.all(np.diff(inside) == 1)


def test_seeds_are_samples_of_the_demonstrations(tmp_path):
    """Seed 0 learns from the file's first steps, another seed from other episodes: the record
    names them, and the programs are trained on different examples."""
    obs, action, episode = synthetic_episodes(np.random.default_rng(6), KNOWN, 12)
    demos = tmp_path / "demos.npz"
    write_demos(demos, obs, action, episode)
    used = {}
    for seed in (0, 1, 2):
        args = PipsArgs(
            demos=str(demos),
            out=str(tmp_path / f"p{seed}.json"),
            steps=720,
            max_depth=1,
            solver="exact",
            seed=seed,
        )
        used[seed] = read_program_record(train(args))["demonstrations"]["episode_ids"]
    assert used[0] == [0, 1, 2]
    assert len({tuple(v) for v in used.values()}) == 3 and all(len(v) == 3 for v in used.values())


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("steps", 0, "PipsArgs.steps must be an int >= 1, got 0"),
        ("window", -1, "PipsArgs.window"),
        ("max_pred_size", 4, "PipsArgs.max_pred_size must be at most 3"),
        ("solver", "cplex", "PipsArgs.solver"),
        ("out", "p.txt", "PipsArgs.out"),
        ("time_budget_s", 0, "PipsArgs.time_budget_s"),
    ],
)
def test_args_are_validated(field, value, message):
    with pytest.raises(ValueError, match=message):
        PipsArgs(demos="d.npz", **{field: value})


@pytest.fixture(scope="module")
def ref_demos(tmp_path_factory, rooms_map_path):
    """A small real recording of Ref on the two-room map (the recorder imported here only)."""
    from socialzoo.bench.demonstrations import DemoConfig, record_demonstrations

    path = tmp_path_factory.mktemp("demos") / "ref.npz"
    config = DemoConfig(
        map=str(rooms_map_path), episodes=10, chunk_episodes=10, env_overrides={"max_steps": 500}
    )
    return record_demonstrations(path, config)


def test_agreement_with_ref_on_held_out_demonstrations(ref_demos, tmp_path):
    """Ref decides from the observation alone, and its GoAlone/Halt test is a lane-and-distance
    comparison the feature set expresses to the centimetre; only its rarer Follow decisions need
    more data. So the program learned from the first 1,500 steps must agree with Ref on the
    held-out steps at least 90% of the time, and beat always answering the commonest action by
    at least half of the remaining gap."""
    args = PipsArgs(
        demos=str(ref_demos),
        out=str(tmp_path / "p.json"),
        steps=1500,
        window=10,
        max_depth=1,
        pool=8,
        partners=200,
        solver="exact",
    )
    out = train(args)
    held = read_program_record(out)["agreement"]["held_out"]
    print(f"agreement with Ref on {held['steps']} held-out steps: {held['agreement']:.3f}")
    assert held["steps"] >= 500
    assert held["agreement"] >= 0.9
    assert held["agreement"] >= held["majority"] + 0.5 * (1 - held["majority"])


@pytest.mark.parametrize("sampling", ["prefix", "windows"])
def test_more_steps_than_the_file_holds_are_refused(tmp_path, sampling):
    """PIPS used the steps there were and recorded the steps asked; BC, GAIL and DAgger refuse."""
    obs, action, episode = synthetic_episodes(np.random.default_rng(6), KNOWN, 2)
    demos = tmp_path / "demos.npz"
    write_demos(demos, obs, action, episode)
    args = PipsArgs(demos=str(demos), out=str(tmp_path / "p.json"), steps=len(action) + 1, sampling=sampling)
    with pytest.raises(DemonstrationError, match=rf"demos\.npz holds \d+ .*, {len(action) + 1} asked"):
        train(args)
    assert not (tmp_path / "p.json").exists()
