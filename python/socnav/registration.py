"""socnav's shipped configs as gymnasium ids: ``gymnasium.make("socnav/Exp2-v0")``.

``import socnav`` registers them (``gymnasium.make("socnav:socnav/Exp2-v0")`` imports it first).
Each id names one shipped config (``exp2`` is ``socnav/Exp2-v0``, ``exp2_sngnn``
``socnav/Exp2Sngnn-v0``, ``lroom_mixed`` ``socnav/LroomMixed-v0``); keyword arguments of
``socnav.make`` (``obs_mode``, ``action_type``, ``render_mode``, ...) pass through, and
``gymnasium.make_vec(id, num_envs=N, vectorization_mode="vector_entry_point")`` gives the batched
``socnav.make_vec`` environment. The environments truncate their own episodes (the config's
``episode.length``), so no ``TimeLimit`` is added.
"""

from __future__ import annotations

from typing import Any, Mapping

import gymnasium as gym

from socnav._socnav import shipped_configs

NAMESPACE = "socnav"
VERSION = 0


def env_id(config: str) -> str:
    """The gymnasium id of a shipped config (``"exp2_sngnn"`` -> ``"socnav/Exp2Sngnn-v0"``)."""
    if config not in shipped_configs():
        raise ValueError(f"{config!r} is not a shipped config ({', '.join(shipped_configs())})")
    name = "".join(part.capitalize() for part in config.split("_"))
    return f"{NAMESPACE}/{name}-v{VERSION}"


def register_envs() -> list[str]:
    """Register every shipped config (again: a no-op); returns the ids."""
    ids = []
    for config in shipped_configs():
        id_ = env_id(config)
        if id_ not in gym.registry:
            gym.register(
                id=id_,
                entry_point="socnav.env:SocNavEnv",
                vector_entry_point="socnav.vector:SocNavVectorEnv",
                kwargs={"config": config},
            )
        ids.append(id_)
    return ids


def env_spec(config: str | Mapping[str, Any], **kwargs: Any) -> gym.envs.registration.EnvSpec:
    """The ``EnvSpec`` that rebuilds ``socnav.make(config, **kwargs)`` with ``gymnasium.make``
    (what a dataset stores so that ``recover_environment()`` works): the registered id of a
    shipped config, else ``socnav/Custom-v0`` with the config (a TOML or SocNavGym YAML path or a dict of
    overrides, JSON-serialisable) in its arguments."""
    if isinstance(config, str) and config in shipped_configs():
        base = gym.spec(env_id(config))
        id_, all_kwargs = base.id, {**base.kwargs, **kwargs}
    else:
        id_, all_kwargs = f"{NAMESPACE}/Custom-v{VERSION}", {"config": config, **kwargs}
    return gym.envs.registration.EnvSpec(
        id=id_,
        entry_point="socnav.env:SocNavEnv",
        vector_entry_point="socnav.vector:SocNavVectorEnv",
        kwargs=all_kwargs,
    )
