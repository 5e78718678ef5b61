"""The benchmark's results store: one SQLite file, one row per finished trial, written as trials
finish, so that an interrupted run resumes and a repeated run reads instead of recomputing."""

from __future__ import annotations

import contextlib
import json
import logging
import math
import sqlite3
import time
from collections.abc import Iterable, Iterator, Mapping, Sequence
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from socialzoo.core.metrics import METRICS

logger = logging.getLogger(__name__)

STORE_FORMAT = "socialzoo-results"
SCHEMA_VERSION = 1
_SQLITE_MAGIC = b"SQLite format 3\x00"

# Columns every trial row has, before its metrics.
TRIAL_COLUMNS = (
    "policy",
    "map",
    "test_set",
    "scenario_index",
    "seed",
    "config_hash",
    "package_version",
    "finished_at",
)
_SQL_TYPE = {"bool": "INTEGER", "int": "INTEGER", "float": "REAL"}
# Seconds to wait for another process's write lock (a write holds it for milliseconds).
BUSY_TIMEOUT = 60.0


def _is_busy(err: sqlite3.OperationalError) -> bool:
    text = str(err).lower()
    return "locked" in text or "busy" in text


class StoreError(Exception):
    """A results file that cannot be used: not a socialzoo results store, corrupted, or too new."""


def _kind(name: str, value: Any) -> str:
    """The column kind of a new metric column: the metric registry's (socialzoo.core.metrics) for
    a registered name, so a column has one type whichever task stores first (the CrowdNav task
    reports its flags and counts as floats); else the type of the first value.

    Raises:
        TypeError: not a bool, int or float, or a value that a registered flag or count cannot
            hold (the message names the metric).
    """
    kind = _value_kind(value)
    registered = METRICS.get(name)
    if registered is None:
        return kind
    if registered.kind == "bool" and value not in (0, 1):
        raise TypeError(f"metric {name!r} is registered as a flag (bool), got {value!r}")
    if registered.kind == "int" and not float(value).is_integer():
        raise TypeError(f"metric {name!r} is registered as a count (int), got {value!r}")
    return registered.kind


def _value_kind(value: Any) -> str:
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int):
        return "int"
    if isinstance(value, float):
        return "float"
    raise TypeError(f"metric values must be bool, int or float, got {type(value).__name__} {value!r}")


def _quote(name: str) -> str:
    if not name.isidentifier():
        raise ValueError(f"metric name {name!r} is not an identifier")
    return f'"{name}"'


class ResultsStore:
    """An SQLite file of benchmark trials, safe to share between runs.

    Tables: meta (format, schema version, package version that created it, metric kinds, and the
    config of the latest run), configs (config hash -> resolved config JSON), and trials (one row
    per trial: policy, map, test set, scenario index, seed, config hash, package version, finish
    time and one column per metric; unique on (policy, test set, scenario index, config hash)).

    A new (or empty) file is created with the schema. An existing file must be a store of this
    format and schema version; anything else (random bytes, a truncated or otherwise corrupted
    database, a file of another kind, a folder) raises StoreError naming the file, and the file is
    left untouched. Each `add` is one committed transaction (SQLite WAL journal), so a killed run
    loses at most the trials it had not handed over yet.

    Several processes (two benchmark runs on the same output directory, say) may open and write
    the same file at once: the schema is created inside a write transaction, and only if it is
    not there yet; every write takes the write lock first (BEGIN IMMEDIATE) and waits up to
    `timeout` seconds for another writer; the WAL journal lets readers read while one writes. A
    trial stored by two runs is kept once (the first), so runs of the same trials simply share
    them.

    Args:
        path: the SQLite file.
        timeout: seconds to wait for another process's write lock before giving up (StoreError).
    """

    def __init__(self, path: str | Path, *, timeout: float = BUSY_TIMEOUT) -> None:
        self.path = Path(path)
        self.timeout = timeout
        if self.path.is_dir():
            # Else a traceback (IsADirectoryError) or, for a folder of size 0, SQLite's "unable to
            # open database file".
            raise StoreError(f"{self.path} is a folder, not a results store: choose another directory")
        if self.path.exists() and self.path.stat().st_size > 0:
            self._check_header()
        else:
            self.path.parent.mkdir(parents=True, exist_ok=True)
        try:
            self._db = sqlite3.connect(self.path, timeout=timeout)
        except sqlite3.Error as err:
            raise StoreError(f"{self.path}: cannot open the results store: {err}") from None
        self._kinds: dict[str, str] = {}
        try:
            if not self._tables():
                with self._write():
                    # Asked again inside the write lock: of two runs opening a new file at once,
                    # one creates the schema and the other finds it there.
                    if not self._tables():
                        self._create()
            self._check_store()
            self._use_wal()
            self._refresh_kinds()
        except sqlite3.DatabaseError as err:
            self._db.close()
            raise StoreError(
                f"{self.path}: corrupted results store ({err}); the file was left as it is"
            ) from None
        except StoreError:
            self._db.close()
            raise

    # ------------------------------------------------------------------ opening
    def _check_header(self) -> None:
        with self.path.open("rb") as f:
            head = f.read(100)  # the SQLite file header
        if head[: len(_SQLITE_MAGIC)] != _SQLITE_MAGIC:
            raise StoreError(
                f"{self.path} is not a socialzoo results store (not an SQLite database); "
                "refusing to use or overwrite it: choose another directory"
            )
        # SQLite reads a page cut short as zeros and keeps no checksums, so a file cut inside its
        # last page can open without complaint with rows silently changed: a database file is a
        # whole number of pages. Not checked while a journal is beside it (another process has the
        # file open, or recovery may still mend it): SQLite checks it then.
        journals = [self.path.with_name(self.path.name + suffix) for suffix in ("-wal", "-journal")]
        if any(j.exists() for j in journals):
            return
        page = int.from_bytes(head[16:18], "big")
        page = 65536 if page == 1 else page  # how SQLite writes its largest page size
        if len(head) < 100 or page < 512 or page & (page - 1):
            raise StoreError(f"{self.path}: corrupted results store (a damaged SQLite header); left as it is")
        size = self.path.stat().st_size
        if size % page:
            raise StoreError(
                f"{self.path}: corrupted results store (truncated: {size} bytes is not a whole number of "
                f"{page}-byte pages); left as it is"
            )

    def _tables(self) -> set[str]:
        return {row[0] for row in self._db.execute("SELECT name FROM sqlite_master WHERE type='table'")}

    def _check_store(self) -> None:
        problems = self._db.execute("PRAGMA quick_check").fetchall()
        if problems != [("ok",)]:
            detail = "; ".join(str(p[0]) for p in problems[:3])
            raise StoreError(f"{self.path}: corrupted results store ({detail}); the file was left as it is")
        tables = self._tables()
        if not {"meta", "configs", "trials"} <= tables or self.meta("format") != STORE_FORMAT:
            raise StoreError(
                f"{self.path} is an SQLite database but not a socialzoo results store "
                f"(tables: {sorted(tables)}); refusing to use or overwrite it"
            )
        version = self.meta("schema_version")
        if version is None or not version.isdigit() or int(version) > SCHEMA_VERSION:
            raise StoreError(
                f"{self.path}: results store schema version {version!r} is not supported "
                f"(this socialzoo reads version {SCHEMA_VERSION} and older)"
            )

    def _use_wal(self) -> None:
        """Switch the file to the WAL journal (kept in the file; a no-op once done)."""
        # Changing the journal mode needs the file to itself: while another process is inside a
        # transaction SQLite may answer "locked" at once instead of waiting, so wait here.
        deadline = time.monotonic() + self.timeout
        while True:
            try:
                self._db.execute("PRAGMA journal_mode=WAL")
                break
            except sqlite3.OperationalError as err:
                if not _is_busy(err) or time.monotonic() > deadline:
                    raise self._busy_error() if _is_busy(err) else err from None
                time.sleep(0.05)
        self._db.execute("PRAGMA synchronous=NORMAL")

    def _create(self) -> None:
        from socialzoo import __version__

        self._db.execute("CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)")
        self._db.execute(
            "CREATE TABLE IF NOT EXISTS configs (config_hash TEXT PRIMARY KEY, config_json TEXT NOT NULL)"
        )
        self._db.execute(
            "CREATE TABLE IF NOT EXISTS trials ("
            "id INTEGER PRIMARY KEY, policy TEXT NOT NULL, map TEXT NOT NULL, test_set TEXT NOT NULL, "
            "scenario_index INTEGER NOT NULL, seed TEXT NOT NULL, config_hash TEXT NOT NULL, "
            "package_version TEXT NOT NULL, finished_at TEXT NOT NULL, "
            "UNIQUE (policy, test_set, scenario_index, config_hash))"
        )
        meta = {
            "format": STORE_FORMAT,
            "schema_version": str(SCHEMA_VERSION),
            "created_with": __version__,
            "created_at": _now(),
            "metric_kinds": "{}",
        }
        self._db.executemany("INSERT OR IGNORE INTO meta VALUES (?, ?)", meta.items())

    @contextlib.contextmanager
    def _write(self) -> Iterator[None]:
        """One write transaction: takes the write lock first (waiting for another writer up to
        the timeout), commits at the end, rolls back on an error."""
        try:
            self._db.execute("BEGIN IMMEDIATE")
        except sqlite3.OperationalError as err:
            if _is_busy(err):
                raise self._busy_error() from None
            raise
        try:
            yield
        except BaseException:
            self._db.rollback()
            raise
        self._db.commit()

    def _busy_error(self) -> StoreError:
        return StoreError(
            f"{self.path}: another process has held the results store's write lock for more than "
            f"{self.timeout:g} s (another run writing to the same directory?); try again when it is "
            "done, or use another output directory"
        )

    def meta(self, key: str) -> str | None:
        """A meta entry, or None."""
        row = self._db.execute("SELECT value FROM meta WHERE key = ?", (key,)).fetchone()
        return None if row is None else str(row[0])

    def _refresh_kinds(self) -> None:
        """Read the metric columns again: another process may have added some."""
        kinds = self._json(self.meta("metric_kinds") or "{}", "meta.metric_kinds")
        if not isinstance(kinds, dict) or not all(k in _SQL_TYPE for k in kinds.values()):
            raise StoreError(f"{self.path}: corrupted results store (meta.metric_kinds is {kinds!r})")
        self._kinds = kinds

    def _json(self, text: str, where: str) -> Any:
        """A JSON value stored in the file; StoreError naming the file and entry if it is damaged."""
        try:
            return json.loads(text)
        except (ValueError, RecursionError) as err:  # JSONDecodeError, or nesting past Python's limit
            raise StoreError(f"{self.path}: corrupted results store ({where} is not JSON: {err})") from None

    # ------------------------------------------------------------------ context
    def close(self) -> None:
        """Close the file (further calls fail)."""
        self._db.close()

    def __enter__(self) -> ResultsStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ configs
    def set_meta(self, key: str, value: str) -> None:
        """Set a free-form meta entry (e.g. "config": the latest run's config JSON)."""
        if key in ("format", "schema_version", "metric_kinds"):
            raise ValueError(f"ResultsStore.set_meta: {key!r} is managed by the store")
        with self._write():
            self._db.execute("INSERT OR REPLACE INTO meta VALUES (?, ?)", (key, value))

    def register_config(self, config_hash: str, config: Mapping[str, Any]) -> None:
        """Record the resolved config behind a config hash (kept as first recorded)."""
        text = json.dumps(config, sort_keys=True)
        with self._write():
            self._db.execute("INSERT OR IGNORE INTO configs VALUES (?, ?)", (config_hash, text))

    def config(self, config_hash: str) -> dict[str, Any] | None:
        """The config recorded for a hash, or None."""
        row = self._db.execute(
            "SELECT config_json FROM configs WHERE config_hash = ?", (config_hash,)
        ).fetchone()
        return None if row is None else self._json(row[0], f"the config of {config_hash}")

    # ------------------------------------------------------------------ trials
    def stored_indices(self, policy: str, test_set: str, config_hash: str) -> set[int]:
        """Scenario indices of the trials already stored for (policy, test set, config hash)."""
        rows = self._db.execute(
            "SELECT scenario_index FROM trials WHERE policy = ? AND test_set = ? AND config_hash = ?",
            (policy, test_set, config_hash),
        )
        return {int(r[0]) for r in rows}

    def _ensure_columns(self, metrics: Mapping[str, Any]) -> None:
        new = {k: _kind(k, v) for k, v in metrics.items() if k not in self._kinds}
        if not new:
            return
        for name, kind in new.items():
            if name in TRIAL_COLUMNS or name == "id":
                raise ValueError(f"metric name {name!r} clashes with a trial column")
            self._db.execute(f"ALTER TABLE trials ADD COLUMN {_quote(name)} {_SQL_TYPE[kind]}")
        self._kinds.update(new)
        self._db.execute(
            "UPDATE meta SET value = ? WHERE key = 'metric_kinds'", (json.dumps(self._kinds, sort_keys=True),)
        )

    def add(self, rows: Iterable[Mapping[str, Any]]) -> int:
        """Store finished trials in one transaction; trials already stored are skipped.

        Args:
            rows: dicts with policy, map, test_set, scenario_index, seed, config_hash, metrics (a
                dict of bool, int or float values) and package_version (default: this package's); a new
                metric's column takes its kind from the metric registry where the name is
                registered (socialzoo.core.metrics), else from its first value.

        Returns:
            The number of new rows.
        """
        from socialzoo import __version__

        rows = list(rows)
        if not rows:
            return 0
        added = 0
        finished = _now()
        with self._write():
            self._refresh_kinds()
            for row in rows:
                metrics = dict(row["metrics"])
                self._ensure_columns(metrics)
                names = [*TRIAL_COLUMNS, *metrics]
                values = [
                    str(row["policy"]),
                    str(row["map"]),
                    str(row["test_set"]),
                    int(row["scenario_index"]),
                    str(int(row["seed"])),
                    str(row["config_hash"]),
                    str(row.get("package_version", __version__)),
                    finished,
                    *metrics.values(),  # sqlite3 stores a bool as the integer 0 or 1
                ]
                cursor = self._db.execute(
                    f"INSERT OR IGNORE INTO trials ({', '.join(map(_quote, names))}) "
                    f"VALUES ({', '.join('?' * len(names))})",
                    values,
                )
                added += cursor.rowcount
        return added

    def rows(
        self,
        *,
        policy: str | None = None,
        test_set: str | None = None,
        config_hash: str | None = None,
        indices: Sequence[int] | None = None,
    ) -> list[dict[str, Any]]:
        """Stored trials matching the filters, ordered by policy, test set, scenario index.

        Returns:
            One dict per trial: the TRIAL_COLUMNS (seed as int) and every metric (bools as bool,
            missing or NaN floats as NaN, missing ints as None).
        """
        where, args = [], []
        for column, value in (("policy", policy), ("test_set", test_set), ("config_hash", config_hash)):
            if value is not None:
                where.append(f"{column} = ?")
                args.append(value)
        self._refresh_kinds()
        columns = [*TRIAL_COLUMNS, *self._kinds]
        sql = f"SELECT {', '.join(map(_quote, columns))} FROM trials"
        if where:
            sql += " WHERE " + " AND ".join(where)
        sql += " ORDER BY policy, test_set, scenario_index, config_hash"
        wanted = None if indices is None else set(int(i) for i in indices)
        out = []
        for values in self._db.execute(sql, args):
            row = dict(zip(columns, values, strict=True))
            if wanted is not None and row["scenario_index"] not in wanted:
                continue
            row["seed"] = int(row["seed"])
            for name, kind in self._kinds.items():
                row[name] = _from_sql(row[name], kind)
            out.append(row)
        return out

    def __len__(self) -> int:
        return int(self._db.execute("SELECT COUNT(*) FROM trials").fetchone()[0])

    @property
    def metric_names(self) -> list[str]:
        """Metric columns, in the order they were first stored."""
        self._refresh_kinds()
        return list(self._kinds)


def trial_row(result: Any, config_hash: str, **names: Any) -> dict[str, Any]:
    """A finished trial (socialzoo.bench.runner.TrialResult) as a row of `ResultsStore.add`, under
    `config_hash`; `names` replace what the trial's own would store (the policy under a label, the
    test set or map under the name a run keeps it by, metrics converted)."""
    return {
        "policy": result.trial.policy,
        "map": result.map,
        "test_set": result.trial.test_set,
        "scenario_index": result.trial.index,
        "seed": result.seed,
        "config_hash": config_hash,
        "metrics": result.metrics,
        **names,
    }


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


def _from_sql(value: Any, kind: str) -> Any:
    if value is None:
        return math.nan if kind == "float" else None
    return {"bool": bool, "int": int, "float": float}[kind](value)
