"""Policy files of the learned baselines: weights as safetensors, plus a JSON header.

The format and its reader live in socialzoo.env.policy_file (the env runs learned crowd models
itself); this module keeps the names where the agents and trainers have always imported them.
"""

from __future__ import annotations

from socialzoo.env.policy_file import HEADER_KEY as HEADER_KEY
from socialzoo.env.policy_file import POLICY_FORMAT as POLICY_FORMAT
from socialzoo.env.policy_file import REQUIRED_KEYS as REQUIRED_KEYS
from socialzoo.env.policy_file import PolicyFileError as PolicyFileError
from socialzoo.env.policy_file import current_env_version as current_env_version
from socialzoo.env.policy_file import env_version as env_version
from socialzoo.env.policy_file import read_policy_file as read_policy_file
from socialzoo.env.policy_file import save_policy_file as save_policy_file
