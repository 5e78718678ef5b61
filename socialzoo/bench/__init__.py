"""The benchmark harness: test sets, batched evaluation, results store, statistics, tables and figures; submodules
are imported where used (`from socialzoo.bench.experiment import run_benchmark`)."""
