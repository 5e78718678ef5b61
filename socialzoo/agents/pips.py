"""PIPS programs: action-selection state machines over the four actions, guarded by predicates on
unit-checked feature expressions; their JSON form and the `pips` policy that runs them."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from socialzoo.agents.base import check_observations
from socialzoo.agents.pips_features import (
    COMPARABLE_UNITS,
    DIMENSIONLESS,
    PaperParts,
    Unit,
    UnitError,
    atom_spec,
    atom_values,
    paper_parts,
)
from socialzoo.core.files import read_json, write_text_atomic
from socialzoo.core.validation import is_finite_number
from socialzoo.env.policy_file import PolicyFileError
from socialzoo.nav.subpolicies import ACTION_NAMES

if TYPE_CHECKING:
    from socialzoo.env.tasks.base import Task

PROGRAM_FORMAT = "socialzoo-pips/1"
# Binary operators that need both sides in the same unit, then those that combine units.
SAME_UNIT_OPS = ("+", "-", "norm")
UNIT_OPS = ("*", "/")
UNARY_OPS = ("abs",)
OPERATORS = (*SAME_UNIT_OPS, *UNIT_OPS, *UNARY_OPS)
COMPARISONS = ("<=", ">=")
JUNCTIONS = ("and", "or")
# Denominators closer to zero than this are taken as +-this (a ratio stays finite).
_TINY = 1e-6
# The binary operators but "/" (which keeps its divisor away from 0, _TINY).
_BINARY = {"+": np.add, "-": np.subtract, "norm": np.hypot, "*": np.multiply}


class ProgramError(ValueError):
    """A PIPS program (or its JSON) that is malformed: the message names the bad node or field."""


class ProgramFileError(ProgramError, PolicyFileError):
    """A PIPS program file that cannot be used: unreadable, not JSON, or not a valid program.

    Both a ProgramError and a PolicyFileError, so `make_policy("pips:FILE")` fails on a bad file
    as every other learned policy does; the message starts with the file.
    """


# ------------------------------------------------------------------------------------ expressions
@dataclass(frozen=True)
class Atom:
    """An atomic feature (socialzoo.agents.pips_features.ATOMS) by name."""

    name: str


@dataclass(frozen=True)
class Op:
    """An operator applied to sub-expressions: + - norm (same unit), * /, abs."""

    op: str
    args: tuple[Expr, ...]


Expr = Atom | Op


def expr_unit(expr: Expr) -> Unit:
    """The unit of an expression.

    Raises:
        UnitError: an operator whose arguments' units disagree (naming both units).
        ProgramError: an unknown feature or operator, or a wrong number of arguments.
    """
    if isinstance(expr, Atom):
        try:
            return atom_spec(expr.name).unit
        except KeyError as err:
            raise ProgramError(err.args[0]) from None
    arity = 1 if expr.op in UNARY_OPS else 2
    if expr.op not in OPERATORS:
        raise ProgramError(f"unknown operator {expr.op!r}; known: {', '.join(OPERATORS)}")
    if len(expr.args) != arity:
        raise ProgramError(f"operator {expr.op!r} takes {arity} argument(s), got {len(expr.args)}")
    units = [expr_unit(a) for a in expr.args]
    if expr.op in UNARY_OPS:
        return units[0]
    if expr.op in SAME_UNIT_OPS:
        if units[0] != units[1]:
            raise UnitError(
                f"{expr.op!r} of {expr_str(expr.args[0])} [{units[0]}] and {expr_str(expr.args[1])} "
                f"[{units[1]}]: the units differ"
            )
        return units[0]
    return units[0] * units[1] if expr.op == "*" else units[0] / units[1]


def expr_eval(expr: Expr, atoms: Mapping[str, np.ndarray]) -> np.ndarray:
    """Values of an expression, given the values of its atoms ((N,) arrays)."""
    if isinstance(expr, Atom):
        return atoms[expr.name]
    vals = [expr_eval(a, atoms) for a in expr.args]
    if expr.op == "abs":
        return np.abs(vals[0])
    a, b = vals
    if expr.op in _BINARY:
        return _BINARY[expr.op](a, b)
    return a / np.where(np.abs(b) < _TINY, np.where(b < 0, -_TINY, _TINY), b)


def expr_atoms(expr: Expr) -> set[str]:
    """Names of the atomic features an expression reads."""
    if isinstance(expr, Atom):
        return {expr.name}
    return set().union(*(expr_atoms(a) for a in expr.args))


def expr_depth(expr: Expr) -> int:
    """Operator nesting depth (an atom is depth 0)."""
    return 0 if isinstance(expr, Atom) else 1 + max(expr_depth(a) for a in expr.args)


def expr_str(expr: Expr) -> str:
    """Readable form, e.g. "(lane60.dist - target_dist)"."""
    if isinstance(expr, Atom):
        return expr.name
    if expr.op in UNARY_OPS or expr.op == "norm":
        return f"{expr.op}({', '.join(expr_str(a) for a in expr.args)})"
    return f"({expr_str(expr.args[0])} {expr.op} {expr_str(expr.args[1])})"


# ------------------------------------------------------------------------------------- predicates
@dataclass(frozen=True)
class Compare:
    """expr <= threshold or expr >= threshold; the threshold is in the expression's unit."""

    expr: Expr
    cmp: str
    threshold: float


@dataclass(frozen=True)
class Junction:
    """A conjunction ("and") or disjunction ("or") of predicates."""

    op: str
    args: tuple[Predicate, ...]


Predicate = Compare | Junction


def check_predicate(pred: Predicate) -> None:
    """Check operators, features, units (only comparable units) and thresholds of a predicate.

    Raises:
        ProgramError, UnitError: naming the bad node.
    """
    if isinstance(pred, Junction):
        if pred.op not in JUNCTIONS:
            raise ProgramError(f"unknown junction {pred.op!r}; known: {', '.join(JUNCTIONS)}")
        if len(pred.args) < 2:
            raise ProgramError(f"{pred.op!r} needs at least 2 arguments, got {len(pred.args)}")
        for a in pred.args:
            check_predicate(a)
        return
    if pred.cmp not in COMPARISONS:
        raise ProgramError(f"unknown comparison {pred.cmp!r}; known: {', '.join(COMPARISONS)}")
    unit = expr_unit(pred.expr)
    if unit not in COMPARABLE_UNITS:
        raise UnitError(f"{expr_str(pred.expr)} has unit {unit}, which is not compared by PIPS programs")
    if not isinstance(pred.threshold, float) or not math.isfinite(pred.threshold):
        raise ProgramError(
            f"threshold of {expr_str(pred.expr)} must be a finite number, got {pred.threshold!r}"
        )


def predicate_eval(pred: Predicate, atoms: Mapping[str, np.ndarray]) -> np.ndarray:
    """(N,) bool: where the predicate holds."""
    if isinstance(pred, Junction):
        vals = [predicate_eval(a, atoms) for a in pred.args]
        out = vals[0].copy()
        for v in vals[1:]:
            out = (out & v) if pred.op == "and" else (out | v)
        return out
    x = expr_eval(pred.expr, atoms)
    return x <= pred.threshold if pred.cmp == "<=" else x >= pred.threshold


def predicate_atoms(pred: Predicate) -> set[str]:
    """Names of the atomic features a predicate reads."""
    if isinstance(pred, Compare):
        return expr_atoms(pred.expr)
    return set().union(*(predicate_atoms(a) for a in pred.args))


def predicate_size(pred: Predicate) -> int:
    """Number of comparisons."""
    return 1 if isinstance(pred, Compare) else sum(predicate_size(a) for a in pred.args)


def predicate_str(pred: Predicate) -> str:
    """Readable form, e.g. "(lane60.dist - target_dist) <= 0.912 m and lane60.mismatch >= 0.79 rad"."""
    if isinstance(pred, Compare):
        unit = expr_unit(pred.expr)
        suffix = "" if unit == DIMENSIONLESS else f" {unit}"
        return f"{expr_str(pred.expr)} {pred.cmp} {pred.threshold:.4g}{suffix}"
    return f" {pred.op} ".join(
        f"({predicate_str(a)})" if isinstance(a, Junction) else predicate_str(a) for a in pred.args
    )


# --------------------------------------------------------------------------------------- programs
@dataclass(frozen=True)
class Transition:
    """Switch to action `target` when `guard` holds."""

    target: int
    guard: Predicate


@dataclass(frozen=True)
class Program:
    """A PIPS state machine: for each current action, its ordered transitions (first match fires).

    For each current action a (the observation's previous action), an ordered list of transitions a -> b, each
    guarded by a predicate: an and/or tree of comparisons f(x) <= t or f(x) >= t of a feature expression f
    with a threshold t in f's unit. The first guard that holds fires; when none does the robot keeps doing a.

    Attributes:
        transitions: action index -> transitions out of it; actions without an entry never change.
    """

    transitions: Mapping[int, tuple[Transition, ...]]

    def __post_init__(self) -> None:
        for state, ts in self.transitions.items():
            if state not in range(len(ACTION_NAMES)):
                raise ProgramError(f"unknown state {state!r}; states are 0..{len(ACTION_NAMES) - 1}")
            for t in ts:
                if t.target not in range(len(ACTION_NAMES)) or t.target == state:
                    raise ProgramError(f"transition {ACTION_NAMES[state]} -> {t.target!r}: bad target action")
                check_predicate(t.guard)

    def atoms(self) -> set[str]:
        """Atomic features the program reads."""
        return set().union(*(predicate_atoms(t.guard) for ts in self.transitions.values() for t in ts))

    def decide(self, obs: np.ndarray) -> np.ndarray:
        """Actions for (N, D) paper-layout observations (the state is each observation's previous
        action); batched, no loop over rows.

        Returns:
            (N,) int64 actions.
        """
        return self.decide_parts(paper_parts(obs))

    def decide_parts(self, parts: PaperParts) -> np.ndarray:
        """`decide` on observations already split by `paper_parts`."""
        atoms = atom_values(parts, self.atoms())
        state = parts.prev_action
        action = state.copy()
        for s, ts in self.transitions.items():
            here = state == s
            if not here.any():
                continue
            # Later transitions first, so that the first guard that holds has the last word.
            for t in reversed(ts):
                action = np.where(here & predicate_eval(t.guard, atoms), t.target, action)
        return action.astype(np.int64)

    def rules(self) -> list[str]:
        """The program as readable rules, one line each."""
        lines = []
        for s in sorted(self.transitions):
            ts = self.transitions[s]
            lines.append(f"in {ACTION_NAMES[s]}:")
            for t in ts:
                lines.append(f"  -> {ACTION_NAMES[t.target]} if {predicate_str(t.guard)}")
            lines.append(f"  otherwise stay in {ACTION_NAMES[s]}")
        return lines or ["(no transitions: keep the first action)"]

    def to_json(self) -> dict[str, Any]:
        """Plain JSON form (see `program_from_json`)."""
        return {
            "format": PROGRAM_FORMAT,
            "actions": list(ACTION_NAMES),
            "states": {
                ACTION_NAMES[s]: [
                    {"to": ACTION_NAMES[t.target], "if": _predicate_to_json(t.guard)}
                    for t in self.transitions[s]
                ]
                for s in sorted(self.transitions)
            },
        }

    def save(self, path: str | Path) -> Path:
        """Write the program as JSON, whole or not at all (core.files.write_text_atomic); returns the path."""
        return write_text_atomic(path, json.dumps(self.to_json(), indent=1) + "\n")


def _expr_to_json(expr: Expr) -> Any:
    if isinstance(expr, Atom):
        return {"feature": expr.name}
    return {"op": expr.op, "args": [_expr_to_json(a) for a in expr.args]}


def _predicate_to_json(pred: Predicate) -> Any:
    if isinstance(pred, Compare):
        return {
            "cmp": pred.cmp,
            "expr": _expr_to_json(pred.expr),
            "threshold": pred.threshold,
            "unit": str(expr_unit(pred.expr)),
        }
    return {"op": pred.op, "args": [_predicate_to_json(a) for a in pred.args]}


def _fields(node: Any, where: str, required: set[str]) -> dict[str, Any]:
    if not isinstance(node, dict):
        raise ProgramError(f"{where}: expected an object, got {type(node).__name__}")
    unknown = sorted(set(node) - required)
    if unknown:
        raise ProgramError(f"{where}: unknown field(s) {unknown}; expected {sorted(required)}")
    missing = sorted(required - set(node))
    if missing:
        raise ProgramError(f"{where}: missing field(s) {missing}")
    return node


def _op_args(node: Any, where: str) -> tuple[Any, list[Any]]:
    """The operator and the argument list of an {"op", "args"} node (an operator or a junction)."""
    node = _fields(node, where, {"op", "args"})
    if not isinstance(node["args"], list):
        raise ProgramError(f"{where}: 'args' must be a list")
    return node["op"], node["args"]


def _expr_from_json(node: Any, where: str) -> Expr:
    if isinstance(node, dict) and "feature" in node:
        name = _fields(node, where, {"feature"})["feature"]
        if not isinstance(name, str):
            raise ProgramError(f"{where}: a feature is named by a string, got {name!r}")
        try:
            atom_spec(name)
        except KeyError as err:
            raise ProgramError(f"{where}: {err.args[0]}") from None
        return Atom(name)
    op, args = _op_args(node, where)
    expr = Op(op, tuple(_expr_from_json(a, f"{where}.args[{i}]") for i, a in enumerate(args)))
    try:
        expr_unit(expr)
    except (ProgramError, UnitError) as err:
        raise type(err)(f"{where}: {err}") from None
    return expr


def _predicate_from_json(node: Any, where: str) -> Predicate:
    if isinstance(node, dict) and "cmp" in node:
        node = _fields(node, where, {"cmp", "expr", "threshold", "unit"})
        expr = _expr_from_json(node["expr"], f"{where}.expr")
        threshold = node["threshold"]
        if not is_finite_number(threshold):
            raise ProgramError(f"{where}: threshold must be a finite number, got {threshold!r}")
        try:
            unit = Unit.parse(node["unit"]) if isinstance(node["unit"], str) else None
        except UnitError as err:
            raise UnitError(f"{where}: {err}") from None
        if unit != expr_unit(expr):
            raise UnitError(
                f"{where}: unit {node['unit']!r} does not match {expr_str(expr)}'s unit {str(expr_unit(expr))!r}"
            )
        pred: Predicate = Compare(expr, node["cmp"], float(threshold))
    else:
        op, args = _op_args(node, where)
        pred = Junction(op, tuple(_predicate_from_json(a, f"{where}.args[{i}]") for i, a in enumerate(args)))
    try:
        check_predicate(pred)
    except (ProgramError, UnitError) as err:
        raise type(err)(f"{where}: {err}") from None
    return pred


def _action_index(name: Any, where: str) -> int:
    if name not in ACTION_NAMES:
        raise ProgramError(f"{where}: unknown action {name!r}; actions: {', '.join(ACTION_NAMES)}")
    return ACTION_NAMES.index(name)


def program_from_json(data: Any, source: str = "program") -> Program:
    """A program from its JSON form, checked node by node; nothing is evaluated.

    Raises:
        ProgramError, UnitError: naming `source`, the path to the bad node and what is wrong
            (an unknown field, operator, feature, action, unit...).
    """
    data = _fields(data, source, {"format", "actions", "states"})
    if data["format"] != PROGRAM_FORMAT:
        raise ProgramError(f"{source}: format {data['format']!r} is not {PROGRAM_FORMAT!r}")
    if data["actions"] != list(ACTION_NAMES):
        raise ProgramError(f"{source}: actions {data['actions']!r} are not {list(ACTION_NAMES)}")
    if not isinstance(data["states"], dict):
        raise ProgramError(f"{source}.states: expected an object")
    transitions: dict[int, tuple[Transition, ...]] = {}
    for name, entries in data["states"].items():
        state = _action_index(name, f"{source}.states")
        if not isinstance(entries, list):
            raise ProgramError(f"{source}.states.{name}: expected a list of transitions")
        ts = []
        for i, entry in enumerate(entries):
            where = f"{source}.states.{name}[{i}]"
            entry = _fields(entry, where, {"to", "if"})
            target = _action_index(entry["to"], f"{where}.to")
            if target == state:
                raise ProgramError(f"{where}: a transition from {name} to itself")
            ts.append(Transition(target, _predicate_from_json(entry["if"], f"{where}.if")))
        transitions[state] = tuple(ts)
    return Program(transitions)


def load_program(path: str | Path) -> Program:
    """Read and check a program file.

    Loading reads JSON and checks every node (operators, features, fields, units); nothing in the file is ever
    executed.

    Raises:
        ProgramFileError: (a ProgramError and a PolicyFileError) no such file, a file that is not
            UTF-8 JSON (random bytes, a truncated file, a file of another kind) or not a valid
            program, a unit error in it included; the message names the file and the bad node.
    """
    path = Path(path)
    data = read_json(path, "PIPS program file", ProgramFileError, missing=ProgramFileError)
    try:
        return program_from_json(data, str(path))
    except (ProgramError, UnitError) as err:
        text = str(err)
        raise ProgramFileError(text if text.startswith(str(path)) else f"{path}: {text}") from None


def shipped_program_path() -> Path:
    """The program shipped with the package (socialzoo/agents/shipped/pips.json)."""
    return Path(str(resources.files("socialzoo.agents") / "shipped" / "pips.json"))


# ----------------------------------------------------------------------------------------- policy
class PipsPolicy:
    """The `pips` policy: runs a PIPS program on paper-layout observations.

    Args:
        program: the program; None loads the shipped one (socialzoo/agents/shipped/pips.json).
    """

    name = "pips"

    def __init__(self, program: Program | None = None) -> None:
        self.program = program if program is not None else load_program(shipped_program_path())

    @classmethod
    def load(cls, path: str | Path) -> PipsPolicy:
        """The policy running the program saved at `path`.

        Raises:
            ProgramFileError: no such file, or not a valid program file (see `load_program`).
        """
        return cls(load_program(path))

    def act(self, obs: np.ndarray, task: Task | None = None) -> np.ndarray:
        """Actions of shape obs.shape[:-1] (see socialzoo.agents.base.Policy.act); the task is
        not read (a program sees the observation only)."""
        obs = check_observations(obs, "PipsPolicy.act")
        lead = obs.shape[:-1]
        return self.program.decide(obs.reshape(-1, obs.shape[-1])).reshape(lead)

    def config(self) -> dict[str, Any]:
        """The program's JSON form."""
        return self.program.to_json()

    def rules(self) -> list[str]:
        """The program as readable rules."""
        return self.program.rules()
