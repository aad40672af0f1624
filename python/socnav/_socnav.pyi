"""Type stubs of the compiled extension ``socnav._socnav`` (python/src/lib.rs, python/src/orca.rs, python/src/viewer.rs).

``mypy.stubtest`` checks them against the built module in CI (scripts/test-all)."""

from typing import Any, final

import numpy as np
import numpy.typing as npt

__all__ = [
    "DISCRETE_ACTIONS",
    "BackendUnavailableError",
    "Batch",
    "ActionError",
    "ConfigError",
    "DeviceError",
    "DisplayError",
    "EnvIndexError",
    "InternalError",
    "ScenarioError",
    "ShapeError",
    "SngnnError",
    "SocNavError",
    "UsageError",
    "Viewer",
    "orca_compute_velocities",
    "orca_compute_velocities_batch",
    "shipped_configs",
    "sngnn_install_from_wheel",
    "sngnn_paths",
    "socnavgym_config_toml",
    "socnavgym_episode_json",
    "write_gif",
]

DISCRETE_ACTIONS: list[list[float]]

class SocNavError(Exception): ...
class ConfigError(SocNavError):
    problems: list[tuple[str | None, str]]

class ScenarioError(SocNavError):
    env: int
    entity: str

class BackendUnavailableError(SocNavError): ...
class SngnnError(SocNavError): ...
class DisplayError(SocNavError): ...
class DeviceError(SocNavError): ...
class UsageError(SocNavError): ...
class InternalError(SocNavError): ...

class ShapeError(SocNavError, ValueError):
    what: str

class ActionError(SocNavError, ValueError):
    env: int | None

class EnvIndexError(SocNavError, IndexError, ValueError):
    env: int
    n_envs: int

@final
class Batch:
    def __new__(
        cls,
        config: str,
        num_envs: int,
        seed: int = 0,
        autoreset_mode: str = "next_step",
        threads: int | None = None,
        overrides: str | None = None,
        toml_text: str | None = None,
        backend: str = "cpu",
    ) -> Batch: ...
    @property
    def num_envs(self) -> int: ...
    @property
    def backend(self) -> str: ...
    @property
    def device(self) -> str: ...
    @property
    def holonomic(self) -> bool: ...
    def config_toml(self) -> str: ...
    def layout(self) -> dict[str, Any]: ...
    @staticmethod
    def keys() -> dict[str, list[str]]: ...
    def reset(self, seed: int | None = None) -> None: ...
    def set_next_seeds(self, seeds: list[int | None]) -> None: ...
    def policy_actions(self, policy: str) -> np.ndarray: ...
    def set_stage_timing(self, on: bool) -> None: ...
    def set_step_outputs(self, *, info: bool = True, interactions: bool = True, events: bool = True) -> None: ...
    def render(self, env: int, size: int = 400, trail: np.ndarray | None = None) -> np.ndarray: ...
    def robot_poses(self) -> np.ndarray: ...
    @property
    def time_step(self) -> float: ...
    def stage_seconds(self) -> dict[str, float]: ...
    def reset_envs(self, mask: npt.NDArray[np.bool_]) -> None: ...
    def step_continuous(self, actions: npt.NDArray[np.float32]) -> None: ...
    def step_discrete(self, actions: npt.NDArray[np.uint32]) -> None: ...
    def send_continuous(self, actions: npt.NDArray[np.float32]) -> None: ...
    def send_discrete(self, actions: npt.NDArray[np.uint32]) -> None: ...
    def recv(self) -> None: ...
    def buffers(self) -> dict[str, npt.NDArray[Any]]: ...
    def get_state(self, env: int) -> str: ...
    def set_state(self, env: int, doc: str) -> None: ...
    def close(self) -> None: ...
    @property
    def closed(self) -> bool: ...

def shipped_configs() -> list[str]: ...
def socnavgym_config_toml(yaml_json: str) -> str: ...
def sngnn_paths() -> tuple[str, str]: ...
def sngnn_install_from_wheel(wheel: str, dest: str) -> int: ...
def orca_compute_velocities(
    positions: npt.NDArray[np.float32],
    velocities: npt.NDArray[np.float32],
    pref_velocities: npt.NDArray[np.float32],
    radius: npt.NDArray[np.float32],
    max_speed: npt.NDArray[np.float32],
    neighbor_dist: npt.NDArray[np.float32],
    max_neighbors: npt.NDArray[np.int64],
    time_horizon: npt.NDArray[np.float32],
    time_horizon_obst: npt.NDArray[np.float32],
    time_step: float,
    obstacles: list[npt.NDArray[np.float32]] | None = None,
) -> npt.NDArray[np.float32]: ...
def orca_compute_velocities_batch(
    positions: list[npt.NDArray[np.float32]],
    velocities: list[npt.NDArray[np.float32]],
    pref_velocities: list[npt.NDArray[np.float32]],
    radius: list[npt.NDArray[np.float32]],
    max_speed: list[npt.NDArray[np.float32]],
    neighbor_dist: list[npt.NDArray[np.float32]],
    max_neighbors: list[npt.NDArray[np.int64]],
    time_horizon: list[npt.NDArray[np.float32]],
    time_horizon_obst: list[npt.NDArray[np.float32]],
    time_step: list[float],
    obstacles: list[list[npt.NDArray[np.float32]]],
) -> list[npt.NDArray[np.float32]]: ...

def write_gif(path: str, frames: list[np.ndarray], frame_ms: int) -> int: ...

@final
class Viewer:
    def __new__(cls, title: str = "socnav") -> Viewer: ...
    def show(self, frame: npt.NDArray[np.uint8], lines: list[str] = ...) -> None: ...
    def is_open(self) -> bool: ...
    def poll(self) -> tuple[list[str], list[str]]: ...
    def close(self) -> None: ...

def socnavgym_episode_json(
    obs: npt.NDArray[np.float32],
    actions: npt.NDArray[np.float32],
    rewards: npt.NDArray[np.float32],
    robot: int,
    offsets: list[int] | tuple[int, int, int, int, int],
    capacities: list[int] | tuple[int, int, int, int, int],
    dim: int,
) -> str: ...
