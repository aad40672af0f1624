"""The live viewer for real: ``socnav play`` in a window under a virtual display, driven by key
presses sent to the X server, its screenshot against the ``rgb_array`` frame of the same state,
its recordings; and ``render_mode="human"``.

scripts/test-viewer runs this under Xvfb with REQUIRE_VIEWER=1 (needs Xvfb, xdotool and xwd:
``apt-get install xvfb xdotool x11-apps``, and the ``socnav`` binary, ``SOCNAV_BIN`` or
target/release/socnav). Elsewhere it skips without a display."""

import json
import os
import shutil
import struct
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

import socnav
from socnav.datasets import played_episodes

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(os.environ.get("SOCNAV_BIN", ROOT / "target" / "release" / "socnav"))
TOOLS = ("xdotool", "xwd")

if os.environ.get("REQUIRE_VIEWER") == "1":
    missing = [t for t in TOOLS if shutil.which(t) is None] + ([] if BIN.exists() else [str(BIN)])
    assert os.environ.get("DISPLAY"), "REQUIRE_VIEWER=1 needs a display (run under xvfb-run)"
    assert not missing, f"REQUIRE_VIEWER=1: missing {missing}"
elif not os.environ.get("DISPLAY") or any(shutil.which(t) is None for t in TOOLS) or not BIN.exists():
    pytest.skip("no display, xdotool/xwd or socnav binary (scripts/test-viewer runs this under Xvfb)",
                allow_module_level=True)


def xdotool(*args: str) -> str:
    return subprocess.run(["xdotool", *args], check=True, capture_output=True, text=True, timeout=20).stdout


def find_window(name: str, timeout: float = 20.0) -> str:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        found = subprocess.run(["xdotool", "search", "--name", name], capture_output=True, text=True)
        if found.stdout.strip():
            return found.stdout.split()[0]
        time.sleep(0.1)
    raise AssertionError(f"no window named {name!r} appeared")


def screenshot(window: str) -> np.ndarray:
    """The window's pixels as the X server holds them (``xwd``, 24-bit TrueColor), (H, W, 3)."""
    data = subprocess.run(["xwd", "-id", window, "-silent"], check=True, capture_output=True, timeout=20).stdout
    header = struct.unpack(">25I", data[:100])
    header_size, width, height = header[0], header[4], header[5]
    byte_order, bits_per_pixel, bytes_per_line, ncolors = header[7], header[11], header[12], header[19]
    assert bits_per_pixel == 32, f"xwd: {bits_per_pixel} bits per pixel"
    start = header_size + 12 * ncolors
    px = np.frombuffer(data[start : start + bytes_per_line * height], np.uint8).reshape(height, bytes_per_line)
    px = px[:, : 4 * width].reshape(height, width, 4)
    # LSBFirst: B, G, R, pad; MSBFirst: pad, R, G, B.
    return px[:, :, [2, 1, 0]] if byte_order == 0 else px[:, :, [1, 2, 3]]


def test_play_moves_on_key_presses_records_and_shows_the_rgb_array_frame(tmp_path):
    config = tmp_path / "short.toml"
    config.write_text("[episode]\nlength = 12\n")
    record = tmp_path / "rec"
    size = 300
    play = subprocess.Popen(
        [str(BIN), "play", "--config", str(config), "--seed", "4", "--record", str(record), "--size", str(size),
         "--speed", "4"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        window = find_window("socnav play")
        xdotool("windowfocus", "--sync", window)
        xdotool("keydown", "Up")
        sidecar = record / "00000000.socnav.json"
        deadline = time.monotonic() + 30
        while not sidecar.exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        xdotool("keyup", "Up")
        assert sidecar.exists(), "the episode did not end and record"
        time.sleep(0.5)  # the final frame is on screen
        shot = screenshot(window)
        # Held for a few frames: the viewer reads key states once a frame (60 Hz).
        xdotool("keydown", "Escape")
        time.sleep(0.2)
        xdotool("keyup", "Escape")
        out, err = play.communicate(timeout=20)
    finally:
        if play.poll() is None:
            play.kill()
    assert play.returncode == 0, err
    assert "1 episodes (1 timeout), 1 recorded" in out

    side = json.loads(sidecar.read_text())
    assert side["seed"] == 4 and side["steps"] == 13 and side["action_type"] == "continuous"
    forward = [a for a in side["actions"] if a == [1.0, 0.0, 0.0]]
    assert len(forward) >= 5, side["actions"]  # the held key drove the robot

    # The same state in the Python environment: the window's scene is its rgb_array frame.
    env = socnav.make(str(config), render_mode="rgb_array", render_size=size)
    env.reset(seed=4)
    for action in side["actions"]:
        env.step(np.asarray(action, dtype=np.float32))
    frame = env.render()
    h, w, _ = frame.shape
    np.testing.assert_array_equal(shot[:h, :w], frame)

    # The recording: 0.1.1's JSON, and the episode rebuilt whole from seed and actions.
    doc = json.loads((record / "00000000.json").read_text())
    assert list(doc) == [str(t) for t in range(13)]
    assert doc["12"]["action"] == side["actions"][12]
    (episode,) = played_episodes(record)
    assert episode.seed == 4 and len(episode) == 13 and episode.outcome == "timeout"
    assert episode.infos["PATH_LENGTH"][-1] > 0.4  # it moved (0.1 m/s forward, at least 5 s)
    np.testing.assert_array_equal(episode.observations[-1], env.unwrapped._buf["obs"][0])


def test_human_render_mode_opens_a_window_and_paces_it():
    env = socnav.make({"base": "exp1", "episode": {"time_step": 0.05}}, render_mode="human", render_size=200)
    assert env.metadata["render_fps"] == pytest.approx(20.0)
    start = time.perf_counter()
    env.reset(seed=2)
    window = find_window("socnav", timeout=5)
    for _ in range(10):
        env.step(np.array([1.0, 0.0, 0.0], np.float32))
    elapsed = time.perf_counter() - start
    assert elapsed >= 10 / 20.0 - 0.05  # 11 frames at 20 fps: about 0.5 s
    assert screenshot(window).shape[0] >= 200
    env.close()
    vec = socnav.make_vec("exp1", num_envs=3, render_mode="human", render_envs=[0, 2], render_size=120)
    vec.reset(seed=0)
    vec.step(np.zeros((3, 3), np.float32))
    find_window("socnav", timeout=5)
    vec.close()

