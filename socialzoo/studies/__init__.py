"""Studies: single experiments composed from the harness (socialzoo.bench) and the trainers
(socialzoo.train), each with its own tables and figures; `socialzoo reproduce` and the command
line call them.

Modules, imported where used (`from socialzoo.studies.lfd import run_lfd_evaluation`):

- `rl_curves`: every checkpoint of the PPO and DQN runs evaluated, the data-efficiency curves,
  and the steps PPO needs to match Ref (`steps_to_match`).
- `rl_training`: the runs those curves evaluate, and `steps_to_reference` (`socialzoo steps-to-ref`).
- `lfd`, `lfd_training`: BC and GAIL at each demonstration size (and PIPS): the runs, their
  evaluation and the LfD table.
- `pips_study`, `pips_study_training`: PIPS over training-set sizes and windows, on validation
  scenarios.
- `human_compare`: a learned human population against the social-force one (`socialzoo
  humans compare`); `human_select`: the checkpoint of a humans run chosen on validation
  scenarios (`socialzoo humans select`).
- `human_report`: how each crowd model walks (`socialzoo humans report`); `crowd_matrix`: every
  robot policy among every crowd model (`socialzoo benchmark --humans A,B,...`).
- `ref_tradeoff`: Ref's parameters against its success and blame, and learned policies with
  their Halt score shifted beside them (`socialzoo study ref-tradeoff`).
- `seeds`: training seeds as an axis: each seed's success per policy and setting aggregated over
  the seeds (mean and IQM with stratified bootstrap intervals, probability of improvement,
  performance profiles; socialzoo.bench.aggregates).

A new study is one module here (a frozen config dataclass, a function that runs it resumably into
a folder, and its table or figure writers); a study's training half may sit beside it as
`<study>_training.py`.
"""
