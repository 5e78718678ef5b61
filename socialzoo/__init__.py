"""socialzoo: a fast batched simulator for robot navigation among people.

The world core (socialzoo.core, socialzoo.humans, socialzoo.nav) is batched numpy arrays with
compiled kernels (numba) for its inner loops; the environment adapters (socialzoo.env) add
Gymnasium and PettingZoo; training and plotting are optional extras.
Importing socialzoo registers the Gymnasium ids (socialzoo/ActionSelection-v2, ...).
"""

__version__ = "0.1.0"


def _register() -> None:
    from socialzoo.env.registration import register_envs

    register_envs()


_register()
