"""Watching: render_mode="rgb_array" frames that pass gymnasium's checks and RecordVideo, vector
frames and tiles, and socnav.record's animations.

The RecordVideo test needs moviepy (gymnasium's video writer): skipped without it unless
REQUIRE_VIDEO=1; scripts/test-sb3 installs it and runs this file."""

import os

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import socnav

SHORT = {"base": "exp2", "episode": {"length": 6}}


def test_single_env_frames_pass_the_env_checker():
    env = socnav.make("exp1", render_mode="rgb_array", render_size=160)
    check_env(env)
    assert env.metadata["render_fps"] == 1.0, "exp1 steps 1 s"
    env.reset(seed=4)
    first = env.render()
    assert first.dtype == np.uint8 and first.shape == (160, 160, 3)
    assert len(np.unique(first.reshape(-1, 3), axis=0)) > 5, "a scene, not a blank"
    for _ in range(5):
        env.step(np.array([1.0, 0.0, 0.0], np.float32))
    assert not np.array_equal(env.render(), first), "the robot moved and left a trail"
    assert socnav.make("exp1").render() is None
    with pytest.raises(ValueError, match="got 'rgb'"):
        socnav.make_vec("exp1", render_mode="rgb")


def test_vector_frames_and_tiles():
    env = socnav.make_vec("exp2", num_envs=6, render_mode="rgb_array", render_envs=[0, 5], render_size=120)
    env.reset(seed=1)
    frames = env.render()
    assert len(frames) == 2 and frames[0].shape[2] == 3 and max(frames[0].shape[:2]) == 120
    assert not np.array_equal(frames[0], frames[1]), "two different episodes"
    same = socnav.make_vec("exp2", num_envs=1, render_mode="rgb_array", render_size=120)
    same.reset(seed=6)
    np.testing.assert_array_equal(same.render()[0], frames[1], "environment 5 plays seed 6")
    grid = socnav.render.tile(list(frames), columns=2, gap=4)
    assert grid.shape == (frames[0].shape[0], 2 * frames[0].shape[1] + 4, 3)
    with pytest.raises(ValueError, match=r"render_envs \[7\] out of range 0..6"):
        socnav.make_vec("exp2", num_envs=6, render_mode="rgb_array", render_envs=[7])


def test_record_writes_a_gif_of_policies_side_by_side(tmp_path):
    path = socnav.record({"goal": "goal", "orca": "orca"}, SHORT, tmp_path / "two.gif", seed=2, size=96)
    data = path.read_bytes()
    assert data[:6] == b"GIF89a"
    # The reset's frame, then one per step until both episodes ended (at most 7 steps: the
    # episode is truncated once its tick exceeds the length 6); a graphic control block each.
    assert 2 <= data.count(b"\x21\xf9\x04") <= 8
    with pytest.raises(ValueError, match="unknown extension"):
        socnav.record("goal", SHORT, tmp_path / "x.avi")


def test_record_video_writes_a_video(tmp_path):
    if os.environ.get("REQUIRE_VIDEO") != "1":
        pytest.importorskip("moviepy", reason="RecordVideo needs moviepy (set REQUIRE_VIDEO=1 to require it)")
    from gymnasium.wrappers import RecordVideo

    env = RecordVideo(socnav.make(SHORT, render_mode="rgb_array", render_size=96), str(tmp_path), episode_trigger=lambda k: True)
    env.reset(seed=0)
    done = False
    while not done:
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        done = terminated or truncated
    env.close()
    videos = list(tmp_path.glob("*.mp4"))
    assert videos and videos[0].stat().st_size > 0


def test_human_mode_without_a_display_raises_display_error(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    env = socnav.make("exp1", render_mode="human")
    assert env.metadata["render_modes"] == ["human", "rgb_array"]
    with pytest.raises(socnav.DisplayError, match="no display"):
        env.reset(seed=0)
    with pytest.raises(ValueError, match="render_mode must be None, 'human' or 'rgb_array', got 'ansi'"):
        socnav.make("exp1", render_mode="ansi")

