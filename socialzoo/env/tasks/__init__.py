"""Robot tasks on the batched core, by name: each task is one class (socialzoo.env.tasks.base.Task)."""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from socialzoo.core.validation import UnknownFieldError, check_int

if TYPE_CHECKING:
    from socialzoo.env.tasks.base import Task

# Registry name -> "module:Class" of the task.
TASKS: dict[str, str] = {
    "action_selection": "socialzoo.env.tasks.action_selection:ActionSelectionTask",
    "crowdnav": "socialzoo.env.tasks.crowdnav:CrowdNavTask",
}


def task_class(task: str | type[Task]) -> type[Task]:
    """The Task class of a registry name, a "module:Class" path, or a class.

    A "module:Class" path is how a registered Gymnasium id names a task defined outside the
    package.

    Raises:
        ValueError: an unknown name or a path that names no Task class.
    """
    from socialzoo.env.tasks.base import Task

    if isinstance(task, type):
        if not issubclass(task, Task):
            raise ValueError(f"task must be a Task subclass, got {task.__name__}")
        return task
    if not isinstance(task, str):
        raise ValueError(f"task must be a task name, a 'module:Class' path or a Task class, got {task!r}")
    path = TASKS.get(task, task)
    if ":" not in path:
        raise ValueError(f"unknown task {task!r}; known tasks: {sorted(TASKS)} (or a 'module:Class' path)")
    module, _, name = path.partition(":")
    try:
        found = getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError) as err:
        raise ValueError(f"task {task!r}: cannot load {path!r} ({err})") from None
    if not (isinstance(found, type) and issubclass(found, Task)):
        raise ValueError(f"task {task!r}: {path!r} is not a Task class")
    return found


# A task's constructor takes these itself (Task.__init__(config, batch_size, **overrides)): as config
# fields they would meet them as the same keyword.
_NOT_FIELDS = {
    "batch_size": "the batch size is the adapter's (num_envs) or the run's (--batch-size)",
    "config": "the config object is given whole, or its fields one by one",
    "task": "the task is the id's",
}


def make_task(task: str | type[Task], batch_size: int = 1, config: Any = None, /, **kwargs: Any) -> Task:
    """A task of B = batch_size rows: `config` (the task's config class) with plain overrides.

    Raises:
        ValueError: an unknown task, a bad batch size, or a bad config field (naming it; also one of
            the constructor's own arguments given as a field, such as --task-config batch_size=2).
    """
    check_int("make_task", "batch_size", batch_size, low=1)
    cls = task_class(task)
    for name in sorted(_NOT_FIELDS.keys() & kwargs.keys()):  # a TypeError too, as Python's own would be
        raise UnknownFieldError(
            f"task {cls.name!r}: {name!r} is not a config field ({_NOT_FIELDS[name]}; got multiple values "
            f"for argument {name!r})"
        )
    return cls(config, batch_size, **kwargs)
