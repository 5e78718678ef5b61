"""Reading the text and JSON files users point at, with one error style: a file that cannot be read raises the
loader's own named error, with the file's path and what the file should have been; and writing files whole or
not at all, records as strict JSON."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any


def read_text(
    path: str | os.PathLike[str],
    what: str,
    error: type[Exception],
    *,
    missing: type[Exception] = FileNotFoundError,
) -> str:
    """The UTF-8 text of `path`, without the byte-order mark that Windows tools write first.

    Args:
        path: the file.
        what: what the file should be, for messages ("map file", "PIPS program").
        error: the loader's named exception class.
        missing: the class raised for a missing file (FileNotFoundError, or the loader's own).

    Raises:
        `missing`: no such file; `error`: not UTF-8 text, or unreadable (a folder, no permission);
            each message starts with the path.
    """
    where = os.fspath(path)
    try:
        # "utf-8-sig" drops a leading BOM (Notepad, Excel's "CSV UTF-8"): kept, it is a character
        # before the first number of a table and makes a JSON file invalid.
        return Path(path).read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise missing(f"{where}: no such {what}") from None
    except UnicodeDecodeError as err:
        raise error(f"{where}: not a {what} (not UTF-8 text: {err.reason} at byte {err.start})") from None
    except OSError as err:
        raise error(f"{where}: unreadable {what} ({err.strerror or err})") from None


def no_file(path: str | os.PathLike[str], what: str = "file") -> str:
    """Why `path` names no `what` to read, for a message: "no such WHAT 'P'", or "'P' is a folder, not a
    WHAT" (a folder is not missing, and saying so sends the user looking for the wrong mistake)."""
    where = os.fspath(path)
    return f"{where!r} is a folder, not a {what}" if Path(path).is_dir() else f"no such {what} {where!r}"


def parse_json(text: str, where: str, what: str, error: type[Exception]) -> Any:
    """The JSON value of `text` read from `where`.

    Raises:
        `error`: not JSON (with the line and column), or a number or a nesting past Python's limits.
    """
    try:
        return json.loads(text)
    except json.JSONDecodeError as err:
        raise error(
            f"{where}: not a {what} (not JSON: {err.msg} at line {err.lineno} column {err.colno})"
        ) from None
    except (ValueError, RecursionError) as err:
        raise error(f"{where}: not a {what} (not JSON: {type(err).__name__}: {err})") from None


def read_json(
    path: str | os.PathLike[str],
    what: str,
    error: type[Exception],
    *,
    kind: type | None = None,
    missing: type[Exception] = FileNotFoundError,
) -> Any:
    """The JSON value of file `path` (read_text, then parse_json), which must be a `kind` (dict,
    list) when given.

    Raises:
        `missing`: no such file; `error`: not UTF-8 JSON, or a value of another kind.
    """
    where = os.fspath(path)
    data = parse_json(read_text(path, what, error, missing=missing), where, what, error)
    if kind is not None and not isinstance(data, kind):
        raise error(f"{where}: not a {what} (a JSON {type(data).__name__}, expected a {kind.__name__})")
    return data


def finite_json(value: Any) -> Any:
    """`value` (dicts, lists and tuples of JSON values) with every float that is not finite (NaN, an
    infinity) as None: JSON has no such numbers, and Python's bare NaN in a file is refused by strict
    readers (JavaScript's JSON.parse, json.loads with parse_constant); a record reads it back as null.
    A numpy float scalar (np.float32, which json cannot write) is a Python float here."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if getattr(getattr(value, "dtype", None), "kind", None) == "f" and getattr(value, "shape", None) == ():
        number = float(value)
        return number if math.isfinite(number) else None
    if isinstance(value, dict):
        return {k: finite_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite_json(v) for v in value]
    return value


def json_text(value: Any, **dumps: Any) -> str:
    """`value` as strict JSON text: non-finite floats as null (finite_json), and allow_nan=False as a
    guard for any that a `default` converter returns; `dumps`: json.dumps's other options.

    Raises:
        ValueError: a non-finite float that finite_json did not reach.
    """
    return json.dumps(finite_json(value), allow_nan=False, **dumps)


def write_text_atomic(path: str | os.PathLike[str], text: str) -> Path:
    """Write a text file whole or not at all: a reader, or another run writing the same file at
    the same time, never sees half of it (a temporary file of this process, then a rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with tmp.open("w", encoding="utf-8", newline="") as f:
            f.write(text)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return path


def write_json(path: str | os.PathLike[str], data: Any) -> Path:
    """Write `data` as indented strict JSON (json_text) with sorted keys, whole or not at all
    (`write_text_atomic`): a reader never sees half of it."""
    return write_text_atomic(path, json_text(data, indent=1, sort_keys=True) + "\n")
