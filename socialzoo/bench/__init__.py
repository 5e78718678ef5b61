"""The benchmark harness: batched and distributed evaluation on fixed test sets (runner), a
resumable SQLite results store (store), confidence intervals (stats), aggregates over training
seeds (aggregates), learned policies stacked in one batch (policy_stack), tables, figures, and the
`benchmark` experiment that ties them together (experiment).

Submodules are imported where used: `from socialzoo.bench.experiment import run_benchmark`.
"""
