"""The evaluation runner's count of rows stepped in its body and its tail, which shows what compacting the tail
(Task.compact, socialzoo.env.compaction) saves."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class RunStats:
    """What a BatchedRunner stepped in its latest `run`: the body (while trials were still
    queued) and the tail (after the queue ran dry, only the last episodes left).

    Attributes:
        body_steps, tail_steps: batch steps.
        body_row_steps, tail_row_steps: env rows stepped (the batch size summed over steps).
        compactions: times the core was shrunk to its live rows.
    """

    body_steps: int = 0
    body_row_steps: int = 0
    tail_steps: int = 0
    tail_row_steps: int = 0
    compactions: int = 0
