"""Tiny-budget training: PPO/SAC/TD3 on both envs, the batched vector env, resume, atomic run directory."""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml

from agents.config import load_train_config
from agents.evaluate import evaluate_policy
from agents.io import write_text_atomic
from agents.runs import load_run
from agents.train import train, train_seed
from moor_env.errors import ConfigError
from tests.agents.conftest import tiny_train_config

RUN_FILES = {"config.yaml", "env_config.yaml", "scene.yaml", "meta.json", "model.zip", "vecnormalize.json",
             "vecnormalize.pkl", "evaluations.json"}


@pytest.mark.parametrize(("algo", "env_id", "vec_env", "n_envs", "extra"), [
    ("sac", "moor_env/AnchorPlan-v0", "dummy", 1, {}),
    ("ppo", "moor_env/AnchorPlan-v0", "subproc", 2, {"hyperparams": {"n_steps": 8, "batch_size": 8}}),
    ("td3", "moor_env/AnchorPlan-v0", "dummy", 1, {}),
    ("ppo", "moor_env/AnchorRelease-v0", "batched", 2, {"hyperparams": {"n_steps": 16, "batch_size": 16}}),
    ("sac", "moor_env/AnchorRelease-v0", "dummy", 1, {}),
])
def test_tiny_training_runs_and_evaluates(tmp_path, tiny_cfg, tiny_scenarios, algo, env_id, vec_env, n_envs, extra):
    data = tiny_train_config(tmp_path, algo=algo, vec_env=vec_env, n_envs=n_envs,
                             total_timesteps=32, **extra)
    data["env"]["id"] = env_id
    if algo == "ppo":
        data["hyperparams"] = extra["hyperparams"]
    (run_dir,) = train(load_train_config(data))
    meta = json.loads((run_dir / "meta.json").read_text())
    assert meta["status"] == "finished" and meta["timesteps"] >= 32
    policy = load_run(run_dir)
    assert policy.env_id == env_id
    res = evaluate_policy(policy, tiny_scenarios[:1], env_id, policy.env_config, progress=False)
    assert res["episodes"][0]["steps"] >= 1 and np.isfinite(res["episodes"][0]["reward"])


def test_run_directory_contents(tmp_path, tiny_cfg):
    cfg = load_train_config(tiny_train_config(tmp_path))
    run_dir = train_seed(cfg, 0)
    names = {p.name for p in run_dir.iterdir()}
    assert RUN_FILES <= names and {"checkpoints", "best", "tb"} <= names
    assert not [p for p in run_dir.rglob("*.tmp")], "temporary files left behind"
    assert load_train_config(run_dir / "config.yaml") == cfg
    meta = json.loads((run_dir / "meta.json").read_text())
    assert meta["seed"] == 0 and meta["versions"]["stable_baselines3"] and "git_commit" in meta
    norm = json.loads((run_dir / "vecnormalize.json").read_text())
    assert len(norm["mean"]) == 27
    scene = yaml.safe_load((run_dir / "scene.yaml").read_text())
    assert scene["installation"]["bottom_chain_length_m"] == 40.0  # the tiny config's scene override
    assert list((run_dir / "tb").rglob("events.out.tfevents.*"))
    evaluations = json.loads((run_dir / "evaluations.json").read_text())
    assert [e["timesteps"] for e in evaluations] == [12, 24]
    latest = json.loads((run_dir / "checkpoints" / "latest.json").read_text())
    assert latest["timesteps"] == 24 and (run_dir / "checkpoints" / latest["folder"] / "replay_buffer.pkl").is_file()
    with pytest.raises(ConfigError) as err:  # the same name again without --resume
        train_seed(cfg, 0)
    assert err.value.key == "name"


def test_resume_continues_from_last_checkpoint(tmp_path, tiny_cfg):
    data = tiny_train_config(tmp_path, total_timesteps=12)
    run_dir = train_seed(load_train_config(data), 0)
    first = json.loads((run_dir / "meta.json").read_text())
    data["total_timesteps"] = 24
    run_dir = train_seed(load_train_config(data), 0, resume=True)
    meta = json.loads((run_dir / "meta.json").read_text())
    assert meta["timesteps"] == 24 and meta["resumed_from"] == "step-000000012"
    assert meta["train_wall_s"] > first["train_wall_s"]
    assert load_run(run_dir).model.num_timesteps == 24
    data["algo"] = "td3"
    with pytest.raises(ConfigError) as err:  # resuming with another config is refused
        train_seed(load_train_config({**data, "hyperparams": {}, "total_timesteps": 36}), 0, resume=True)
    assert err.value.key == "config"


def test_interrupted_write_keeps_previous_file(tmp_path):
    path = tmp_path / "a.json"
    write_text_atomic(path, "old")

    class Interrupted(Exception):
        pass

    def failing(tmp):
        tmp.write_text("partial")
        raise Interrupted

    from agents.io import write_atomic

    with pytest.raises(Interrupted):
        write_atomic(path, failing)
    assert path.read_text() == "old" and list(tmp_path.iterdir()) == [path]


def test_main_job_trains_evaluates_and_prints_the_table(tmp_path, tiny_cfg, tiny_scenarios, capsys):
    from agents.main import main
    from agents.scenarios import save_scenarios

    save_scenarios(tiny_scenarios[:2], tmp_path / "s.json")
    cfg_path = tmp_path / "t.yaml"
    cfg_path.write_text(yaml.safe_dump(tiny_train_config(tmp_path / "runs", total_timesteps=12)))
    args = ["--config", str(cfg_path), "--scenarios", str(tmp_path / "s.json"), "--jobs", "1",
            "--population", "2", "--iterations", "1"]
    assert main(args) == 0
    out = capsys.readouterr().out
    for row in ("| t |", "| crew |", "| random |", "| optimiser |"):
        assert row in out
    report = tmp_path / "runs" / "t" / "evaluation"
    assert {"evaluation.json", "evaluation.md", "distributions.png", "episode.png"} <= {p.name for p in
                                                                                        report.iterdir()}


def test_main_job_on_plan_v1_shows_the_bundled_policy(tmp_path, capsys):
    """AnchorPlan-v1: the preset beside the bundled policy and the three baselines, with the statistics."""
    from agents.main import main
    from agents.scenarios import held_out_sites, save_scenarios

    save_scenarios(held_out_sites(2), tmp_path / "s.json")
    cfg = tiny_train_config(tmp_path / "runs", total_timesteps=8, hyperparams={"learning_starts": 4,
                                                                              "batch_size": 4, "buffer_size": 100})
    cfg["env"] = {"id": "moor_env/AnchorPlan-v1", "config": "anchor-plan", "overrides": {}}
    cfg["eval"] = {"freq_steps": 8, "episodes": 1}
    (tmp_path / "t.yaml").write_text(yaml.safe_dump(cfg))
    args = ["--config", str(tmp_path / "t.yaml"), "--scenarios", str(tmp_path / "s.json"), "--jobs", "1",
            "--population", "2", "--iterations", "1"]
    assert main(args) == 0
    out = capsys.readouterr().out
    for row in ("| plan-v1-sac | AnchorPlan-v1 |", "| t | AnchorPlan-v1 |", "| crew |", "| random |", "| optimiser |"):
        assert row in out
    assert "Task check" in out and "plan-v1-sac beats crew" in out
    records = json.loads((tmp_path / "runs" / "t" / "evaluation" / "rl_evaluation.json").read_text())
    assert {r["policy"] for r in records["episodes"]} == {"plan-v1-sac", "t", "crew", "random", "optimiser"}
    assert all(r["required_speed_m_s"] > 15.0 for r in records["episodes"])


def test_bundled_policy_loads_by_name_and_acts_on_five_levers():
    from agents.bundle import bundled_names, bundled_path
    from agents.train_rllib import load_run_policies

    assert "plan-v1-sac" in bundled_names()
    meta = json.loads((bundled_path("plan-v1-sac") / "meta.json").read_text())
    assert meta["reproduce"] and meta["status"] == "finished"
    (policy,) = load_run_policies(bundled_path("plan-v1-sac"))
    assert policy.env_id == "moor_env/AnchorPlan-v1"
    a = policy.act(np.zeros(9, np.float32), {})
    assert a.shape == (5,) and (np.abs(a) <= 1.0).all()
