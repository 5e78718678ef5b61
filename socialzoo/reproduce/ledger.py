"""Where a reproduction keeps its items (DIR/<hash>/: settings.json, timings.json, the parts' folders), and how long
each part took."""

from __future__ import annotations

import logging
import os
import platform
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from socialzoo.core.files import read_json, write_json
from socialzoo.reproduce.plan import VOLATILE_FIELDS, Settings, settings_hash

logger = logging.getLogger(__name__)

SETTINGS_FILE = "settings.json"
TIMINGS_FILE = "timings.json"


class LedgerError(ValueError):
    """A work folder's record (settings.json, timings.json) that cannot be read: not UTF-8 JSON,
    cut short, or of another kind; the message names the file."""


class SettingsMismatch(LedgerError):
    """A work folder that holds items of other settings (or whose settings.json is unreadable, so
    that whose items they are cannot be told)."""


def machine() -> dict[str, Any]:
    """A description of this machine for the report (CPU count, platform, Python), with the facts
    that decide torch-trained numbers (socialzoo.train.machine.machine_facts) under "facts"."""
    from socialzoo.train.machine import machine_facts

    return {
        "cpus": os.cpu_count(),
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "python": platform.python_version(),
        "facts": machine_facts(),
    }


class Ledger:
    """The work folder DIR/<hash>/ of one settings: its settings record and the parts' timings.

        DIR/<hash>/settings.json     the settings these items were made with (refused if they differ)
        DIR/<hash>/timings.json      every session of every part: start, wall seconds, finished or not
        DIR/<hash>/demos/ rl/ lfd/ performance/ transfer/     the parts' items

    Items are stored as they finish by the pieces that make them (training run folders, demonstration
    chunks, SQLite trial stores), so a rerun after an interruption continues where it stopped. A
    part's wall time is the sum of its sessions, so an interrupted and resumed part counts every
    second spent.

    Args:
        out_dir: the reproduction's output folder DIR.
        settings: the settings.

    Raises:
        SettingsMismatch: (a LedgerError) DIR/<hash>/settings.json records other settings, or is
            unreadable (random bytes, a truncated file, a file of another kind); naming the file.
    """

    def __init__(self, out_dir: str | Path, settings: Settings) -> None:
        self.out_dir = Path(out_dir)
        self.settings = settings
        self.hash = settings_hash(settings)
        self.work = self.out_dir / self.hash
        self.work.mkdir(parents=True, exist_ok=True)
        record: dict[str, Any] = {"hash": self.hash, "settings": settings.to_json()}
        file = self.work / SETTINGS_FILE
        if file.exists():
            stored = read_json(file, "settings record; not mixing items with it", SettingsMismatch, kind=dict)
            if (
                stored.get("hash") != self.hash
                or not isinstance(stored.get("settings"), dict)
                or _comparable(stored["settings"]) != _comparable(record["settings"])
            ):
                raise SettingsMismatch(f"{self.work} holds items of other settings ({file}); not mixing them")
        write_json(file, record)

    def path(self, *parts: str) -> Path:
        """A path inside the work folder."""
        return self.work.joinpath(*parts)

    def timings(self) -> dict[str, Any]:
        """{part: {"sessions": [...], "seconds": total, "finished": bool}} as stored.

        Raises:
            LedgerError: an unreadable timings.json, or one whose parts are not such records
                (naming the file).
        """
        file = self.work / TIMINGS_FILE
        if not file.exists():
            return {}
        data = read_json(file, "timings record", LedgerError, kind=dict)
        for part, entry in data.items():
            if not isinstance(entry, dict) or not isinstance(entry.get("sessions"), list):
                raise LedgerError(f"{file}: unreadable timings record ({part!r} has no list of sessions)")
        return data

    def _record(self, part: str, session: dict[str, Any]) -> None:
        data = self.timings()
        entry = data.setdefault(part, {"sessions": []})
        entry["sessions"].append(session)
        entry["seconds"] = round(sum(s["seconds"] for s in entry["sessions"]), 1)
        # The part's own work: sessions that computed something (a rerun that only reads back
        # stored items is recorded, but it is not the time the part takes).
        entry["work_seconds"] = round(sum(s["seconds"] for s in entry["sessions"] if s.get("computed")), 1)
        entry["finished"] = any(s["finished"] for s in entry["sessions"])
        entry["machine"] = machine()
        write_json(self.work / TIMINGS_FILE, data)

    @contextmanager
    def timed(self, part: str, backend: str) -> Iterator[dict[str, Any]]:
        """Time one session of a part. The caller sets session["computed"] = number of items it
        made (0 when everything was read back); an exception (Ctrl-C too) records the session as
        unfinished and propagates."""
        session: dict[str, Any] = {
            "started": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
            "backend": backend,
            "computed": None,
            "finished": False,
        }
        start = time.perf_counter()
        try:
            yield session
            session["finished"] = True
        finally:
            session["seconds"] = round(time.perf_counter() - start, 1)
            if session["computed"] is None:
                session["computed"] = 1  # interrupted: it was working
            self._record(part, session)
            logger.info(
                "%s: %.1f s (%s)", part, session["seconds"], "done" if session["finished"] else "stopped"
            )


def _comparable(settings: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in settings.items() if k not in VOLATILE_FIELDS}
