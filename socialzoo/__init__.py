"""socialzoo: a fast batched simulator for robot navigation among people.

The world core (socialzoo.core, socialzoo.humans, socialzoo.nav) is numpy only; the environment
adapters (socialzoo.env) add Gymnasium and PettingZoo; training and plotting are optional extras.
"""

__version__ = "0.1.0"
