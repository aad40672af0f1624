"""socnav.metrics against hand-computed means and against an aggregation written out here, on a
real batched rollout: the table's rule (docs/spec.md 8.3) is the Rust ``episodes::Aggregate`` one,
means over episodes with non-finite values skipped per key."""

import math

import numpy as np
import pytest

import socnav
from socnav.metrics import EPISODE_KEYS, EpisodeLog, Summary, aggregate

K = len(EPISODE_KEYS)
SUCCESS = EPISODE_KEYS.index("success")
MIN_HUMAN = EPISODE_KEYS.index("MINIMUM_DISTANCE_TO_HUMAN")
RETURN = EPISODE_KEYS.index("return")


def row(**values):
    r = np.zeros(K, dtype=np.float32)
    for key, v in values.items():
        r[EPISODE_KEYS.index(key)] = v
    return r


def test_keys_are_the_rust_episode_keys():
    assert EPISODE_KEYS == tuple(socnav._socnav.Batch.keys()["episode"])
    assert K == 32 and EPISODE_KEYS[:2] == ("return", "length")


def test_hand_computed_means_skip_non_finite_values():
    # The case of the Rust unit test (episodes.rs), plus a NaN and a third episode.
    log = EpisodeLog()
    log.add_rows(row(success=1, MINIMUM_DISTANCE_TO_HUMAN=np.inf, length=10, STL=np.nan))
    log.add_rows(row(success=0, MINIMUM_DISTANCE_TO_HUMAN=2.0, length=20, STL=0.5))
    log.add_rows(row(success=0, MINIMUM_DISTANCE_TO_HUMAN=3.0, length=60, STL=0.25))
    s = log.summary()
    assert s.episodes == 3 == len(log)
    assert s["success"] == pytest.approx(1 / 3)
    assert s["MINIMUM_DISTANCE_TO_HUMAN"] == 2.5, "the +inf episode does not count"
    assert s.finite["MINIMUM_DISTANCE_TO_HUMAN"] == 2
    assert s["STL"] == 0.375, "NaN is skipped like inf"
    assert s["length"] == 30.0
    assert s.finite["length"] == 3


def test_a_key_finite_in_no_episode_has_a_nan_mean():
    s = aggregate(np.stack([row(MINIMUM_OBSTACLE_DISTANCE=np.inf), row(MINIMUM_OBSTACLE_DISTANCE=-np.inf)]))
    assert math.isnan(s["MINIMUM_OBSTACLE_DISTANCE"]) and s.finite["MINIMUM_OBSTACLE_DISTANCE"] == 0
    assert s["success"] == 0.0 and s.episodes == 2


def test_empty_log():
    log = EpisodeLog()
    s = log.summary()
    assert s.episodes == 0 and all(math.isnan(v) for v in s.means.values())
    assert log.rows().shape == (0, K)
    assert log.table()["return"].shape == (0,)


def test_add_takes_masked_rows_and_copies_them():
    n = 4
    stats = {k: np.arange(n, dtype=np.float32) + j for j, k in enumerate(EPISODE_KEYS)}
    info = {"episode": stats, "_episode": np.array([False, True, False, True])}
    log = EpisodeLog()
    assert log.add(info) == 2
    for v in stats.values():
        v[:] = -7.0  # the next step overwrites the buffers
    table = log.table()
    np.testing.assert_array_equal(table["return"], [1.0, 3.0])
    np.testing.assert_array_equal(table["length"], [2.0, 4.0])
    assert log.add({"PATH_LENGTH": np.zeros(n)}) == 0, "a step where no episode ended"
    assert log.add({"episode": stats, "_episode": np.zeros(n, bool)}) == 0
    assert len(log) == 2


def test_add_reads_sb3_style_info_lists():
    episode = {"r": 1.5, "l": 12, "t": 0.1, **{k: 0.0 for k in EPISODE_KEYS}}
    episode.update({"return": 1.5, "length": 12.0, "success": 1.0})
    log = EpisodeLog()
    assert log.add([{"TimeLimit.truncated": False}, {"episode": episode}, {}]) == 1
    assert log.summary()["success"] == 1.0 and log.summary()["length"] == 12.0


def test_bad_rows_are_rejected():
    log = EpisodeLog()
    with pytest.raises(ValueError, match=r"shape \(n, 32\)"):
        log.add_rows(np.zeros((2, 5)))
    with pytest.raises(KeyError, match="success"):
        log.add_rows({k: 0.0 for k in EPISODE_KEYS if k != "success"})
    with pytest.raises(KeyError, match="unknown episode statistic"):
        log.summary()["SUCESS"]
    assert len(log) == 0


def test_custom_keys_extend_and_clear():
    a = EpisodeLog(keys=("return", "success"))
    a.add_rows([[1.0, 1.0], [3.0, 0.0]])
    b = EpisodeLog(keys=("return", "success"))
    b.add_rows([5.0, 1.0])
    a.extend(b)
    assert a.summary().means == {"return": 3.0, "success": 2 / 3}
    with pytest.raises(ValueError, match="different statistics"):
        a.extend(EpisodeLog())
    a.clear()
    assert len(a) == 0 and a.summary().episodes == 0


def test_table_as_dict_and_as_pandas():
    log = EpisodeLog()
    log.add_rows(np.stack([row(success=1, length=5), row(collision=1, length=9)]))
    table = log.table()
    assert list(table) == list(EPISODE_KEYS)
    assert all(v.dtype == np.float32 and v.shape == (2,) for v in table.values())
    table["length"][0] = 99.0  # a copy: the log is unchanged
    assert log.summary()["length"] == 7.0
    pd = pytest.importorskip("pandas", reason="pandas is not installed")
    df = log.table(as_pandas=True)
    assert isinstance(df, pd.DataFrame) and df.shape == (2, K)
    assert df["collision"].tolist() == [0.0, 1.0]
    assert aggregate(df).means == log.summary().means


def test_summary_formats_like_the_cli():
    log = EpisodeLog()
    log.add_rows(np.stack([row(success=1, length=10, STL=0.5), row(timeout=1, length=201)]))
    text = str(log.summary())
    assert "episodes finished: 2 (mean length 105.5 steps)" in text
    assert "success 50.0 %" in text and "timeout 50.0 %" in text
    assert "STL    0.2500" in text
    d = log.summary().to_dict()
    assert d["episodes"] == 2 and d["STL"] == 0.25
    assert isinstance(log.summary(), Summary)


def test_means_are_sequential_float64_sums_as_in_rust():
    # Rust adds each f32 value as f64 in episode order; numpy's pairwise np.mean may differ in
    # the last bits, the log must not.
    rng = np.random.default_rng(1)
    rows = (rng.standard_normal((5000, K)) * 10 ** rng.uniform(-3, 6, (5000, K))).astype(np.float32)
    rows[rng.random((5000, K)) < 0.1] = np.inf
    s = aggregate(rows)
    for j, key in enumerate(EPISODE_KEYS):
        total, count = 0.0, 0
        for v in rows[:, j].tolist():
            if math.isfinite(v):
                total += v
                count += 1
        assert s[key] == total / count, key


def independent_means(rows):
    """The table's rule written out with Python floats, one episode at a time."""
    means = {}
    for j, key in enumerate(EPISODE_KEYS):
        values = [r[j] for r in rows if math.isfinite(r[j])]
        total = 0.0
        for v in values:
            total += v
        means[key] = total / len(values) if values else math.nan
    return means


def test_log_of_a_batched_rollout_matches_an_independent_aggregation():
    # Up to one walking human: episodes without humans have an infinite minimum human distance.
    config = {"base": "exp1", "counts": {"dynamic_humans": [0, 1]}}
    n = 32
    env = socnav.make_vec(config, num_envs=n, seed=3, action_type="discrete")
    env.reset(seed=3)
    rng = np.random.default_rng(0)
    log = EpisodeLog()
    rows, ended, per_env = [], 0, np.zeros(n, int)
    for _ in range(600):
        _, _, terminated, truncated, info = env.step(rng.integers(0, 7, n))
        log.add(info)
        if "_episode" in info:
            mask = info["_episode"]
            ended += int(mask.sum())
            np.testing.assert_array_equal(mask, terminated | truncated)
            for i in np.flatnonzero(mask):
                rows.append([float(info["episode"][k][i]) for k in EPISODE_KEYS])
                per_env[i] += 1
        else:
            assert not (terminated | truncated).any()
    s = log.summary()
    assert s.episodes == len(log) == ended == len(rows)
    assert ended > 60 and (per_env > 0).all()
    expected = independent_means(rows)
    for key in EPISODE_KEYS:
        assert s[key] == expected[key] or (math.isnan(s[key]) and math.isnan(expected[key])), key
    # The rollout exercises the skipping: some episodes had no human, some had one.
    assert 0 < s.finite["MINIMUM_DISTANCE_TO_HUMAN"] < s.episodes
    assert s.finite["MINIMUM_DISTANCE_TO_HUMAN"] == sum(math.isfinite(r[MIN_HUMAN]) for r in rows)
    # Outcome flags partition the episodes (a wall collision is also an object collision).
    assert s["success"] + s["collision"] + s["timeout"] + s["out_of_map"] == pytest.approx(1.0)
    # Rows come back in the order they ended.
    np.testing.assert_array_equal(log.table()["return"], np.float32([r[RETURN] for r in rows]))
    assert log.table()["length"].max() <= 201


def test_the_key_subsets_come_from_the_extension_and_agree():
    # The outcome rates are the means of the episode outcome flags, which are 0.1.1's boolean
    # info keys in lower case; the integer info keys are info keys too.
    keys = socnav._socnav.Batch.keys()
    assert set(keys["outcomes"]) <= set(keys["episode"])
    assert set(keys["bool_info"]) | set(keys["int_info"]) <= set(keys["info"])
    assert {k.lower() for k in keys["bool_info"]} == set(keys["outcomes"])
    assert socnav.metrics._OUTCOMES == tuple(keys["outcomes"])
    from socnav.socnavgym import BOOL_INFO, INT_INFO

    assert BOOL_INFO == frozenset(keys["bool_info"]) and INT_INFO == {"FAILURE_TO_PROGRESS", "TIME_TO_COLLISION"}
