"""Learned human policies at inference: shared-parameter walkers read from a policy file, run in numpy.

They live in socialzoo.env.human_policy (the env drives learned people itself, EnvConfig.people);
this module keeps the names where the agents, trainers and harness have always imported them.
"""

from __future__ import annotations

from socialzoo.env.human_policy import ACTION_FRAMES as ACTION_FRAMES
from socialzoo.env.human_policy import HUMAN_POLICY_NAMES as HUMAN_POLICY_NAMES
from socialzoo.env.human_policy import LEARNED as LEARNED
from socialzoo.env.human_policy import POLICY_NAME as POLICY_NAME
from socialzoo.env.human_policy import SOCIAL_FORCE as SOCIAL_FORCE
from socialzoo.env.human_policy import LearnedHumanPolicy as LearnedHumanPolicy
from socialzoo.env.human_policy import check_human_spec as check_human_spec
from socialzoo.env.human_policy import make_human_policy as make_human_policy
from socialzoo.env.human_policy import split_human_spec as split_human_spec
