"""socialzoo: a fast batched simulator for robot navigation among people.
Importing socialzoo registers the Gymnasium ids (socialzoo/ActionSelection-v2, ...)."""

__version__ = "0.1.0"


def _register() -> None:
    from socialzoo.env.registration import register_envs

    register_envs()


_register()
