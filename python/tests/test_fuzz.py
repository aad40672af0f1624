"""Fuzzing the Python API with hypothesis: `make`/`make_vec` arguments, override dicts, actions
of every dtype and shape, reset options and state documents. The invariant: a call succeeds, or
raises a documented exception (socnav's errors, ValueError, TypeError, IndexError, OverflowError,
MemoryError, KeyError, and the OSError of its kind for a config path that cannot be read); never
a Rust panic (`pyo3_runtime.PanicException`), never a crash of the interpreter, and a batch that
refused a call still steps.

`HYPOTHESIS_PROFILE=long` runs the long profile (100,000 examples in all, see benches/RESULTS.md);
skipped when hypothesis is not installed, unless REQUIRE_HYPOTHESIS=1 (scripts/test-fuzz)."""

import json
import math
import os

import numpy as np
import pytest

if os.environ.get("REQUIRE_HYPOTHESIS") == "1":
    import hypothesis  # noqa: F401  (REQUIRE_HYPOTHESIS=1: a missing hypothesis is a failure)
else:
    pytest.importorskip(
        "hypothesis",
        reason="hypothesis is not installed (pip install 'socnav[fuzz]'; set REQUIRE_HYPOTHESIS=1 "
        "to make its absence a failure)",
    )

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import socnav

settings.register_profile(
    "ci", max_examples=150, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck)
)
# 100,000 examples over the 5 targets.
settings.register_profile(
    "long", max_examples=20_000, deadline=None, suppress_health_check=list(HealthCheck)
)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

#: What a bad argument may raise: documented errors, never a panic. A config string that names no
#: shipped config is read as a path: FileNotFoundError, IsADirectoryError (``""`` is ``.``), ...
EXPECTED = (socnav.SocNavError, ValueError, TypeError, IndexError, OverflowError, MemoryError, KeyError, OSError)

SHIPPED = [c for c in socnav.shipped_configs() if "sngnn" not in c]

anything = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=12),
    st.lists(st.integers(-5, 50), max_size=3),
    st.dictionaries(st.text(max_size=6), st.integers(), max_size=2),
)


def expect_clean(call):
    """Run ``call``; a raise must be a documented exception (a panic is a BaseException
    subclass outside ``EXPECTED``, so it propagates and fails the test)."""
    try:
        return call()
    except EXPECTED:
        return None


@given(
    config=st.one_of(st.sampled_from(SHIPPED), st.text(max_size=10), anything),
    num_envs=st.one_of(st.integers(-3, 6), st.sampled_from([2**31, 2**63, 10**9]), anything),
    seed=st.one_of(st.none(), st.integers(-(2**65), 2**65), anything),
    obs_mode=st.one_of(st.sampled_from(["dict", "flat"]), anything),
    action_type=st.one_of(st.sampled_from(["continuous", "discrete"]), anything),
    autoreset_mode=st.one_of(st.sampled_from(["next_step", "same_step", "disabled"]), anything),
    threads=st.one_of(st.none(), st.integers(-2, 3), anything),
)
def test_make_vec_arguments(config, num_envs, seed, obs_mode, action_type, autoreset_mode, threads) -> None:
    envs = expect_clean(
        lambda: socnav.make_vec(
            config,
            num_envs,
            seed=seed,
            obs_mode=obs_mode,
            action_type=action_type,
            autoreset_mode=autoreset_mode,
            threads=threads,
        )
    )
    if envs is not None:
        expect_clean(lambda: envs.step(envs.action_space.sample()) if envs.reset(seed=1) else None)
        envs.close()


#: Keys of the TOML layout, with values drawn around their bounds.
OVERRIDE_KEYS = [
    ("episode", "length"), ("episode", "time_step"), ("robot", "radius"), ("robot", "max_speed"),
    ("robot", "kinematics"), ("human", "diameter"), ("human", "max_speed"), ("human", "fov_angle"),
    ("human", "policy"), ("room", "shape"), ("room", "size_x"), ("room", "margin"),
    ("counts", "dynamic_humans"), ("counts", "tables"), ("counts", "group_size"),
    ("objects", "table_width"), ("objects", "laptop_length"), ("reward", "kind"),
    ("observation", "padded"), ("bogus", "key"),
]
values = st.one_of(
    st.floats(-1e3, 1e3),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-5, 40),
    st.lists(st.integers(-3, 12), min_size=0, max_size=3),
    st.sampled_from(["square", "L", "holonomic", "diff-drive", "orca", "sngnn", "", "?"]),
    st.booleans(),
    st.none(),
)


@given(
    base=st.sampled_from(SHIPPED),
    edits=st.lists(st.tuples(st.sampled_from(OVERRIDE_KEYS), values), min_size=1, max_size=4),
)
def test_override_dicts(base, edits) -> None:
    overrides: dict = {"base": base}
    for (section, key), value in edits:
        overrides.setdefault(section, {})[key] = value
    try:
        envs = socnav.make_vec(overrides, 2, seed=0)
    except socnav.ConfigError as e:
        assert e.problems, "a ConfigError lists its problems"
        return
    except (socnav.ScenarioError, TypeError, ValueError):
        return
    try:
        envs.reset(seed=0)
        obs, reward, *_ = envs.step(envs.action_space.sample())
    except socnav.ScenarioError as e:  # a valid config whose room jams for this episode
        assert e.entity and f"environment {e.env}" in str(e)
        return
    assert np.isfinite(reward).all()
    envs.close()


DTYPES = [np.float32, np.float64, np.float16, np.int64, np.int32, np.uint32, np.uint8, np.bool_, np.complex64, object]


@st.composite
def arrays(draw):
    dtype = draw(st.sampled_from(DTYPES))
    shape = draw(st.lists(st.integers(0, 4), min_size=0, max_size=3))
    size = int(np.prod(shape)) if shape else 1
    raw = draw(
        st.lists(
            st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-(2**40), 2**40)),
            min_size=size,
            max_size=size,
        )
    )
    with np.errstate(all="ignore"):
        try:
            return np.array(raw, dtype=np.float64).astype(dtype).reshape(shape)
        except (OverflowError, ValueError, TypeError):
            return np.zeros(shape, dtype=dtype)


@given(
    action_type=st.sampled_from(["continuous", "discrete"]),
    actions=st.one_of(arrays(), anything, st.lists(st.floats(allow_nan=True), max_size=7)),
)
def test_actions_of_every_dtype_and_shape(action_type, actions) -> None:
    envs = socnav.make_vec("exp1", 3, seed=0, action_type=action_type)
    envs.reset(seed=0)
    expect_clean(lambda: envs.step(actions))
    # Whatever was refused, the batch steps on.
    obs, reward, *_ = envs.step(envs.action_space.sample())
    assert np.isfinite(reward).all()
    envs.close()


@given(
    seed=st.one_of(st.none(), st.integers(-(2**65), 2**65), st.lists(st.integers(-2, 2**64), max_size=4), anything),
    options=st.one_of(st.none(), st.dictionaries(st.sampled_from(["reset_mask", "seed", "x"]), anything, max_size=2)),
)
def test_reset_options(seed, options) -> None:
    envs = socnav.make_vec("exp1", 3, seed=0, autoreset_mode="disabled")
    expect_clean(lambda: envs.reset(seed=seed, options=options))
    envs.reset(seed=0)
    obs, reward, *_ = envs.step(envs.action_space.sample())
    assert np.isfinite(reward).all()
    envs.close()


@given(
    cut=st.integers(0, 10_000),
    key=st.sampled_from(["x", "y", "theta", "speed", "goal", "role", "group", "id"]),
    value=anything,
    text=st.booleans(),
)
def test_state_documents(cut, key, value, text) -> None:
    batch = socnav._socnav.Batch("exp3", 2, seed=0)
    batch.reset(0)
    doc = batch.get_state(0)
    if text:
        candidate = doc[: cut % (len(doc) + 1)]
    else:
        parsed = json.loads(doc)
        parsed["state"]["humans"][0][key] = value if not (isinstance(value, float) and math.isnan(value)) else "nan"
        candidate = json.dumps(parsed, allow_nan=True)
    before = batch.get_state(1)
    try:
        batch.set_state(1, candidate)
    except EXPECTED:
        assert batch.get_state(1) == before, "a refused document changed the environment"
    batch.step_discrete(np.zeros(2, dtype=np.uint32))
    assert np.isfinite(batch.buffers()["obs"]).all()
