"""socnav.train: the baselines run, log, checkpoint, resume where they stopped, export agents that
load and act, and PPO learns exp1 within minutes.

Skipped when torch is not importable, unless REQUIRE_TORCH=1 (then it fails); scripts/test-sb3
runs it in the torch environment it shares with the SB3 tests."""

import csv
import json
import os
from pathlib import Path

import numpy as np
import pytest

if os.environ.get("REQUIRE_TORCH") == "1":
    import torch  # noqa: F401  (REQUIRE_TORCH=1: a missing torch is a failure)
else:
    pytest.importorskip("torch", reason="torch is not installed (pip install './python[train]')")

import torch

import socnav
from socnav.train import dqn, export, load, ppo

SHORT = "exp1"


def _rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def test_dqn_runs_logs_resumes_and_exports(tmp_path):
    out = tmp_path / "dqn"
    args = dqn.Args(config=SHORT, steps=1024, out=str(out), num_envs=16, threads=1, learning_starts=256,
                    batch_size=32, buffer_size=4096, log_every=512, target_update=512)
    dqn.train(args)
    rows = _rows(out / "progress.csv")
    assert [int(r["step"]) for r in rows] == [512, 1024]
    for key in ("loss", "epsilon", "time_env_s", "time_learn_s", "time_sim_s", "time_reward_s"):
        assert key in rows[0]
    assert float(rows[-1]["time_reward_s"]) > 0.0 and float(rows[-1]["time_sim_s"]) >= float(rows[-1]["time_reward_s"])
    saved = torch.load(out / "checkpoint.pt", weights_only=False)
    assert saved["step"] == 1024 and saved["replay"]["obs"].shape == (1024, 597)
    # Run again with more steps: it resumes at 1024 and appends to the same log (the epsilon
    # schedule follows the new total).
    args.steps = 2048
    dqn.train(args)
    rows = _rows(out / "progress.csv")
    assert [int(r["step"]) for r in rows] == [512, 1024, 1536, 2048]
    agent_file = export(out / "checkpoint.pt", tmp_path / "agent.pt")
    assert agent_file.stat().st_size < 2_000_000, "float16 weights"
    agent = load(agent_file)
    assert agent.kind == "dqn" and agent.action_type == "discrete" and agent.config == SHORT
    env = socnav.make_vec(SHORT, num_envs=4, obs_mode="flat", action_type="discrete")
    obs, _ = env.reset(seed=0)
    a = agent(obs, env)
    assert a.shape == (4,) and a.dtype == np.uint32 and a.max() < 7
    result = socnav.evaluate(str(agent_file), {"base": SHORT, "episode": {"length": 20}}, episodes=4, seed=9)
    assert result.episodes == 4


def test_a_resumed_run_equals_an_uninterrupted_one(tmp_path):
    base = dict(config=SHORT, num_envs=8, threads=1, learning_starts=128, batch_size=16, buffer_size=2048,
                log_every=256, target_update=256)
    dqn.train(dqn.Args(steps=768, out=str(tmp_path / "whole"), **base))
    dqn.train(dqn.Args(steps=768, chunk_steps=384, out=str(tmp_path / "parts"), **base))
    dqn.train(dqn.Args(steps=768, out=str(tmp_path / "parts"), **base))
    whole = torch.load(tmp_path / "whole" / "checkpoint.pt", weights_only=False)
    parts = torch.load(tmp_path / "parts" / "checkpoint.pt", weights_only=False)
    for k, v in whole["q"].items():
        torch.testing.assert_close(parts["q"][k], v, rtol=0, atol=0, msg=f"q.{k}")
    np.testing.assert_array_equal(parts["replay"]["obs"], whole["replay"]["obs"])


def test_the_progress_log_follows_the_checkpoint(tmp_path):
    """A run killed between checkpoints logged rows its resumption logs again; a run killed before
    its first checkpoint left a log of a run that starts over. Neither may show twice."""
    base = dict(config=SHORT, num_envs=8, threads=1, learning_starts=128, batch_size=16, buffer_size=2048,
                log_every=128, target_update=256)
    dqn.train(dqn.Args(steps=512, out=str(tmp_path / "whole"), **base))
    expected = [int(r["step"]) for r in _rows(tmp_path / "whole" / "progress.csv")]
    assert expected == [128, 256, 384, 512]

    parts = tmp_path / "parts"
    dqn.train(dqn.Args(steps=512, chunk_steps=256, out=str(parts), **base))
    with open(parts / "progress.csv", "a") as f:  # what a kill after step 256's checkpoint leaves
        f.write("384,1,1\n")
    dqn.train(dqn.Args(steps=512, out=str(parts), **base))
    assert [int(r["step"]) for r in _rows(parts / "progress.csv")] == expected

    fresh = tmp_path / "fresh"
    fresh.mkdir()
    (fresh / "progress.csv").write_text("step,x\n128,1\n256,1\n")  # no checkpoint.pt beside it
    dqn.train(dqn.Args(steps=512, out=str(fresh), **base))
    assert [int(r["step"]) for r in _rows(fresh / "progress.csv")] == expected


def test_a_socnavgym_yaml_config_trains(tmp_path):
    """`socnav.train` takes a SocNavGym 0.1.1 YAML path like any config (the core converts it)."""
    yaml = Path(__file__).resolve().parents[2] / "tests/data/golden/socnavgym/configs/exp1_no_sngnn.yaml"
    out = tmp_path / "yaml"
    args = dqn.Args(config=str(yaml), steps=256, out=str(out), num_envs=8, threads=1, learning_starts=64,
                    batch_size=16, buffer_size=512, log_every=128, target_update=128)
    dqn.train(args)
    assert [int(r["step"]) for r in _rows(out / "progress.csv")] == [128, 256]


@pytest.mark.parametrize("action_type", ["discrete", "continuous"])
def test_ppo_runs_and_exports(tmp_path, action_type):
    out = tmp_path / action_type
    ppo.train(ppo.Args(config=SHORT, steps=1024, out=str(out), num_envs=8, threads=1, rollout_steps=64,
                       action_type=action_type, log_every=512))
    assert [int(r["step"]) for r in _rows(out / "progress.csv")] == [512, 1024]
    agent = load(export(out / "checkpoint.pt", tmp_path / f"ppo-{action_type}.pt"))
    env = socnav.make_vec(SHORT, num_envs=3, obs_mode="flat", action_type=action_type)
    obs, _ = env.reset(seed=1)
    a = agent(obs, env)
    assert a.shape == ((3,) if action_type == "discrete" else (3, 3))
    if action_type == "continuous":
        assert np.all(np.abs(a) <= 1.0) and np.all(a[:, 1] == 0.0)


def test_errors_name_the_problem(tmp_path):
    with pytest.raises(ValueError, match="no agent 'nope'"):
        load("nope")
    with pytest.raises(ValueError, match="--action-type must be"):
        ppo.train(ppo.Args(out=str(tmp_path / "x"), action_type="both", steps=10))
    agent = load(export_tiny(tmp_path))
    with pytest.raises(ValueError, match="flat observations of 597 floats"):
        agent(np.zeros((2, 5), np.float32))


def test_bad_arguments_are_listed_before_anything_runs(tmp_path):
    bad = dqn.Args(out=str(tmp_path / "bad"), buffer_size=0, batch_size=-1, seed=-1, max_minutes=float("nan"),
                   chunk_steps=2.5, gamma=1.5)
    with pytest.raises(ValueError) as err:
        dqn.train(bad)
    for needle in ("--buffer-size must be at least 1, got 0", "--batch-size must be at least 1, got -1",
                   "--seed must be an integer", "--max-minutes must be a positive number of minutes, got nan",
                   "--chunk-steps must be at least 1, got 2.5", "--gamma must be in [0, 1], got 1.5"):
        assert needle in str(err.value), str(err.value)
    assert not (tmp_path / "bad").exists(), "a refused run made its directory"
    with pytest.raises(ValueError, match=r"--minibatches 100 is more than a rollout's 16 samples"):
        ppo.Args(num_envs=2, rollout_steps=8, minibatches=100).check()
    from socnav.train.__main__ import main

    assert main(["dqn", "--max-minutes", "nan", "--out", str(tmp_path / "cli")]) == 2
    with pytest.raises(SystemExit):  # argparse: an int option takes no fraction
        main(["dqn", "--chunk-steps", "2.5"])


def test_a_run_directory_is_never_spoiled(tmp_path):
    """Every log row has the episode columns (the first one may come before any episode ends);
    export never writes over a checkpoint; a moved run resumes; a resume refused for its
    arguments writes nothing; a file that is not an agent is named."""
    run = tmp_path / "tiny"
    agent = export_tiny(tmp_path)
    rows = _rows(run / "progress.csv")
    assert "success" in rows[0] and float(rows[0]["episodes_logged"]) == 0 and rows[0]["success"] == "nan"
    checkpoint = run / "checkpoint.pt"
    before = checkpoint.read_bytes()
    for out in (checkpoint, tmp_path / "elsewhere" / ".." / "tiny" / "checkpoint.pt"):
        with pytest.raises(ValueError, match="a training checkpoint"):
            export(checkpoint, out)
    assert checkpoint.read_bytes() == before
    moved = tmp_path / "moved"
    moved.mkdir()
    for f in run.iterdir():
        if f.is_file():
            (moved / f.name).write_bytes(f.read_bytes())
    (moved / "args.json").unlink()  # the checkpoint's own arguments decide
    base = dict(config=SHORT, num_envs=8, threads=1, learning_starts=10**9, log_every=64)
    with pytest.raises(ValueError, match=r"other arguments \{'num_envs': \(8, 4\)\}"):
        dqn.train(dqn.Args(steps=128, out=str(moved), **{**base, "num_envs": 4}))
    assert not (moved / "args.json").exists()
    dqn.train(dqn.Args(steps=128, out=str(moved), **base))
    assert [int(r["step"]) for r in _rows(moved / "progress.csv")] == [64, 128]
    junk = tmp_path / "junk.pt"
    junk.write_bytes(b"not a checkpoint")
    with pytest.raises(ValueError, match="junk.pt: not a socnav agent file"):
        load(junk)
    with pytest.raises(ValueError, match="export its agent first"):
        load(checkpoint)
    assert load(agent).kind == "dqn"


def export_tiny(tmp_path):
    out = tmp_path / "tiny"
    dqn.train(dqn.Args(config=SHORT, steps=64, out=str(out), num_envs=8, threads=1, learning_starts=10**9, log_every=64))
    return export(out / "checkpoint.pt", tmp_path / "tiny.pt")


# Success rates of PPO after 300,000 steps of exp1 (64 environments, 2 threads), greedy on the 200
# episodes of seeds 10000.. (measured on the 2-core machine, with other work beside it): seed 0 0.520,
# seed 1 0.630, seed 2 0.620; the random policy 0.030. The threshold is the lowest, less a margin
# for other CPUs' floating point (torch's kernels differ across instruction sets).
PPO_SUCCESS_THRESHOLD = 0.40


def test_ppo_learns_exp1_within_minutes(tmp_path):
    """Done-when of the training issue: PPO trains on exp1 in well under 5 minutes (about 25 s of
    the 2-core machine) to a success rate at least 3 times the random policy's and at least
    PPO_SUCCESS_THRESHOLD."""
    out = tmp_path / "ppo"
    ppo.train(ppo.Args(config="exp1", steps=300_000, out=str(out), seed=0, num_envs=64, threads=2, log_every=100_000))
    agent = load(export(out / "checkpoint.pt", tmp_path / "agent.pt"))
    trained = socnav.evaluate(agent, "exp1", episodes=200, seed=10_000).summary()["success"]
    random = socnav.evaluate("random", "exp1", episodes=200, seed=10_000).summary()["success"]
    print(f"PPO success {trained:.3f}, random {random:.3f}")
    assert trained >= 3 * random, (trained, random)
    assert trained >= PPO_SUCCESS_THRESHOLD, trained


def _fake_run(directory, name, config, success):
    run = directory / name
    run.mkdir()
    (run / "args.json").write_text('{"config": "%s"}' % config)
    with open(run / "progress.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["step", "success", "collision"])
        for k, s in enumerate(success):
            w.writerow([(k + 1) * 1000, s, 1 - s])
    return run


def test_plot_draws_learning_curves_by_world(tmp_path):
    from socnav.train.__main__ import main
    from socnav.train.plot import load_run, plot_runs

    a = _fake_run(tmp_path, "ppo-exp2-dsrnn", "exp2", [0.1, 0.5, 0.7])
    b = _fake_run(tmp_path, "ppo-exp2-sngnn", "exp2_sngnn", [0.2, 0.6, 0.8])
    c = _fake_run(tmp_path, "dqn-exp3-dsrnn", "exp3", [0.0, 0.3])
    runs = [load_run(p) for p in (a, b, c)]
    # Both rewards of one experiment share a panel; a run's colour key drops its world.
    assert [r.world for r in runs] == ["exp2", "exp2", "exp3"]
    assert [r.series for r in runs] == ["ppo-dsrnn", "ppo-sngnn", "dqn-dsrnn"]
    assert runs[1].columns["success"] == [0.2, 0.6, 0.8] and runs[1].columns["step"] == [1000, 2000, 3000]
    out = plot_runs([a, b, c], tmp_path / "curves.png", metrics=["success", "collision"])
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # A progress CSV outside its run directory, with its arguments beside it (docs/results/).
    (tmp_path / "ppo-exp2-dsrnn.progress.csv").write_bytes((a / "progress.csv").read_bytes())
    (tmp_path / "ppo-exp2-dsrnn.args.json").write_bytes((a / "args.json").read_bytes())
    alone = load_run(tmp_path / "ppo-exp2-dsrnn.progress.csv")
    assert (alone.name, alone.world) == ("ppo-exp2-dsrnn", "exp2")
    with pytest.raises(ValueError, match="'nope'"):
        plot_runs([a], tmp_path / "x.png", metrics=["nope"])
    with pytest.raises(FileNotFoundError, match="no progress CSV"):
        load_run(tmp_path / "missing")
    assert main(["plot", str(a), "--metric", "nope", "--out", str(tmp_path / "y.png")]) == 2
    assert main(["plot", str(a), str(b), "--metric", "success", "--out", str(tmp_path / "z.svg")]) == 0
    assert (tmp_path / "z.svg").read_text().lstrip().startswith("<?xml")


def test_paper_mode_takes_sb3s_schedule_per_environment_step(tmp_path):
    """`--mode paper`: one gradient step of 32 every 4 environment steps whatever the batch size,
    the deep ReLU Q-network of stable_dqn.py; flags given after the preset still win."""
    paper = dqn.Args.for_mode("paper")
    assert (paper.network, paper.learning_rate, paper.batch_size, paper.train_freq) == ("sb3-deep", 1e-4, 32, 4)
    assert (paper.buffer_size, paper.learning_starts, paper.target_update) == (1_000_000, 50_000, 10_000)
    assert dqn.Args.for_mode("paper-text").network == "dueling"
    # 64 environments: 16 a batch step; 6 environments: 1 or 2, 3 every 2 batch steps.
    assert dqn.gradient_steps(paper, 0, 64) == 16
    assert [dqn.gradient_steps(paper, s, s + 6) for s in range(0, 24, 6)] == [1, 2, 1, 2]
    assert dqn.gradient_steps(dqn.Args(), 0, 64) == 1
    out = tmp_path / "paper"
    args = dqn.Args.for_mode("paper", config=SHORT, steps=512, out=str(out), num_envs=16, threads=1,
                             learning_starts=128, buffer_size=2048, log_every=256)
    dqn.train(args)
    rows = _rows(out / "progress.csv")
    # Learning from step 128 (the batch step that reaches it updates too): (512 - 112) / 4.
    assert int(rows[-1]["gradient_steps"]) == (512 - 112) // 4
    agent = load(export(out / "checkpoint.pt", tmp_path / "paper.pt"))
    assert agent.network == "sb3-deep" and isinstance(agent.net, dqn.PlainQ)
    with pytest.raises(ValueError, match="--network must be one of dueling, sb3-deep, got 'wide'"):
        dqn.Args(network="wide").check()
    with pytest.raises(ValueError, match="unknown --mode 'fast'"):
        dqn.Args.for_mode("fast")


#: Episodes of a shipped agent that may end otherwise than recorded: greedy actions whose Q values
#: (or logits) tie to within the float rounding of another CPU's matrix kernels can flip, and one
#: flipped action changes the rest of its episode.
OUTCOME_FLIPS = 2


def test_shipped_agents_score_as_recorded():
    """Every shipped agent plays the episodes `scripts/agent-outcomes` recorded (seeds 1,000,000
    on of its experiment) greedily and ends each as recorded, up to OUTCOME_FLIPS episodes; so a
    change that breaks an agent cannot land. `scripts/agent-outcomes --write` records them anew
    when an agent is retrained on purpose."""
    tracked = json.loads((Path(__file__).parent / "data/agent_outcomes.json").read_text())
    assert sorted(tracked) == socnav.train.shipped()
    for name, record in tracked.items():
        result = socnav.evaluate(load(name), record["config"], episodes=len(record["endings"]), seed=record["seed"])
        flips = [k for k, (a, b) in enumerate(zip(result.endings.tolist(), record["endings"])) if a != b]
        assert len(flips) <= OUTCOME_FLIPS, f"{name}: episodes {flips} end otherwise than recorded"


def _entity_batch(config="exp2", n=4):
    from socnav.train import entity

    env = socnav.make_vec(socnav.with_overrides(config, entity.CONFIG_OVERRIDES), num_envs=n, obs_mode="flat")
    obs, _ = env.reset(seed=3)
    return env, obs.copy(), entity.Layout.of(env.unwrapped._batch.layout())


def test_the_entity_encoder_ignores_the_order_and_the_padding_of_records():
    """Permutation invariance over the human records, and absent (all-zero) records change
    nothing: the input of a crowd of any size and order is read as a set."""
    from socnav.train import entity

    env, obs, layout = _entity_batch()
    torch.manual_seed(0)
    encoder = entity.EntityEncoder(layout)
    memory = entity.FrameMemory()
    x = torch.from_numpy(memory.features(obs))
    base = encoder(x)
    humans = env.unwrapped._batch.layout()["entities"]["humans"]
    start, count = humans
    assert count >= 3
    shuffled = x.clone()
    for half in (0, layout.dim):  # the observation and its change, in the same order
        block = shuffled[:, half + start : half + start + count * entity.RECORD].reshape(-1, count, entity.RECORD)
        block[:] = block[:, torch.tensor([2, 0, 1, *range(3, count)])].clone()
    torch.testing.assert_close(encoder(shuffled), base, rtol=1e-5, atol=1e-6)
    # One more record, absent (all zeros, as padding is): the same output from the same weights.
    wider = entity.Layout(dim=layout.dim + entity.RECORD, robot=layout.robot, entities=layout.entities, count=layout.count + 1)
    padded_encoder = entity.EntityEncoder(wider)
    padded_encoder.load_state_dict(encoder.state_dict())
    pad = torch.zeros(x.shape[0], entity.RECORD)
    padded_x = torch.cat([x[:, : layout.dim], pad, x[:, layout.dim :], pad], dim=1)
    torch.testing.assert_close(padded_encoder(padded_x), base, rtol=1e-5, atol=1e-6)
    # ... whatever its change half holds.
    padded_x[:, -entity.RECORD :] = 7.0
    torch.testing.assert_close(padded_encoder(padded_x), base, rtol=1e-5, atol=1e-6)


def test_frame_memory_forgets_at_an_episode_start():
    from socnav.train import entity

    memory = entity.FrameMemory()
    a = np.arange(6, dtype=np.float32).reshape(2, 3)
    np.testing.assert_array_equal(memory.features(a), np.concatenate([a, np.zeros_like(a)], axis=1))
    memory.remember(a)
    b = a + 1.0
    np.testing.assert_array_equal(memory.features(b)[:, 3:], np.ones_like(a))
    np.testing.assert_array_equal(memory.features(b[1:], rows=np.array([False, True]))[:, 3:], [[1.0, 1.0, 1.0]])
    memory.restart(np.array([True, False]), b)
    np.testing.assert_array_equal(memory.features(b)[:, 3:], [[0, 0, 0], [1, 1, 1]])


def test_the_entity_layout_needs_the_robot_velocity():
    from socnav.train import entity

    env = socnav.make_vec("exp2", num_envs=1, obs_mode="flat")
    with pytest.raises(ValueError, match="robot_velocity"):
        entity.Layout.of(env.unwrapped._batch.layout())


@pytest.mark.parametrize("action_type", ["discrete", "continuous"])
def test_entity_ppo_trains_resumes_exports_and_evaluates(tmp_path, action_type):
    """The entity network end to end: a run in two chunks, its agent exported and evaluated on
    a config without the robot's velocity (the agent's ``config_overrides`` add it), and its
    greedy actions equal to the exported network's on the same inputs."""
    out = tmp_path / "entity"
    args = dict(config="exp2", steps=1024, out=str(out), num_envs=8, threads=1, rollout_steps=32,
                action_type=action_type, network="entity", log_every=256, snapshot_every=512)
    ppo.train(ppo.Args(**args, chunk_steps=512))
    ppo.train(ppo.Args(**args))
    assert [int(r["step"]) for r in _rows(out / "progress.csv")] == [256, 512, 768, 1024]
    snapshots = sorted(p.name for p in (out / "snapshots").iterdir())
    assert snapshots == ["step-0000000512.pt", "step-0000001024.pt"]
    snap = torch.load(out / "snapshots" / snapshots[1], weights_only=True)
    assert all(v.dtype == torch.float32 for v in snap["state_dict"].values()) and snap["steps"] == 1024
    from socnav.train.select import select

    chosen, rows = select(out, episodes=4, num_envs=2)
    assert [r["steps"] for r in rows] == [512, 1024]
    best = max(rows, key=lambda r: (r["success"], -r["collision"], r["steps"]))
    assert chosen.read_bytes() == (out / "snapshots" / best["snapshot"]).read_bytes()
    table = _rows(out / "selection.csv")
    assert [r["selected"] for r in table] == [str(r is best) for r in rows]
    saved = torch.load(out / "checkpoint.pt", weights_only=False)
    assert saved["network"] == "entity" and saved["reward_scale"] is not None
    agent = load(export(out / "checkpoint.pt", tmp_path / "entity.pt"))
    assert agent.network == "entity" and agent.config_overrides == {"observation": {"robot_velocity": True}}
    result = socnav.evaluate(agent, "exp2", episodes=6, seed=50, num_envs=3)
    assert len(result.seeds) == 6 and np.isfinite(result.summary()["success"])
    gif = socnav.record({"agent": agent, "goal": "goal"}, "exp2", tmp_path / "side-by-side.gif", episodes=1, seed=50)
    assert gif.stat().st_size > 0
    env, obs, layout = _entity_batch(n=2)
    agent.reset_memory()
    a = agent(obs, env)
    with torch.no_grad():
        out_net = agent.net(torch.from_numpy(np.concatenate([obs, np.zeros_like(obs)], axis=1))).numpy()
    expected = out_net.argmax(1) if action_type == "discrete" else np.clip(out_net, -1, 1)
    if action_type == "continuous" and not env.unwrapped._batch.holonomic:
        expected[:, 1] = 0.0
    np.testing.assert_array_equal(a, expected)
    with pytest.raises(ValueError, match="--network must be"):
        ppo.train(ppo.Args(out=str(tmp_path / "x"), network="transformer", steps=10))
