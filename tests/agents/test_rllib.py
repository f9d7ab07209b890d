"""Ray RLlib PPO (agents/train_rllib.py): config validation, and a two-iteration run on a local Ray instance
whose env runner is a separate worker process (so the env registration for Ray workers is exercised)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from agents.evaluate import evaluate_policy, evaluate_targets
from agents.train_rllib import RllibPolicy, is_rllib_run, load_rllib_config, load_run_policies, main, train_rllib
from moor_env.errors import ConfigError


@pytest.mark.parametrize(("overrides", "key"), [
    ({"ppo.minibatch_size": 4096}, "ppo.minibatch_size"),
    ({"ppo.lr": -1.0}, "ppo.lr"),
    ({"ppo.n_steps": 8}, "ppo.n_steps"),
    ({"env_runners.num_env_runners": -1}, "env_runners.num_env_runners"),
    ({"env_runners.rollout_fragment_length": 0}, "env_runners.rollout_fragment_length"),
    ({"model.fcnet_hiddens": [64, 0]}, "model.fcnet_hiddens[1]"),
    ({"env.id": "CartPole-v1"}, "env.id"),
])
def test_bad_config_names_the_key(overrides, key):
    with pytest.raises(ConfigError) as err:
        load_rllib_config("rllib-release", overrides)
    assert err.value.key == key


def test_settings_rllib_refuses_are_a_config_error():
    from agents.train_rllib import checked_ppo_config  # noqa: PLC0415
    from moor_env.envs.config import load_env_config  # noqa: PLC0415

    # two runners of 64-step fragments cannot fill a 64-step batch
    cfg = load_rllib_config("rllib-tiny", {"env_runners.num_env_runners": 2})
    with pytest.raises(ConfigError, match="rollout_fragment_length"):
        checked_ppo_config(cfg, load_env_config("tiny"))


def test_command_line_refuses_a_bad_key_with_exit_code_2(capsys):
    assert main(["--config", "rllib-tiny", "--set", "ppo.num_epochs=0"]) == 2
    assert "ppo.num_epochs=0" in capsys.readouterr().err


@pytest.fixture(scope="module")
def local_ray():
    """A local two-CPU Ray instance for this module (the run joins it instead of starting its own)."""
    import ray  # noqa: PLC0415

    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield ray
    ray.shutdown()


@pytest.mark.slow
def test_two_iterations_on_local_ray_write_a_loadable_run(tmp_path, local_ray, tiny_cfg, tiny_scenarios):
    cfg = load_rllib_config("rllib-tiny", {"out_dir": str(tmp_path)})
    run_dir, meta = train_rllib(cfg)

    assert meta["status"] == "finished" and meta["iterations"] == 2
    assert meta["env_steps"] >= cfg.total_timesteps and meta["env_steps_per_s"] > 0.0
    rows = json.loads((run_dir / "progress.json").read_text())
    assert [r["iteration"] for r in rows] == [1, 2]
    # sampled by the remote env runner: at least one finished episode with a finite return
    assert rows[-1]["episodes"] >= 1 and np.isfinite(rows[-1]["episode_return_mean"])
    assert json.loads((run_dir / "checkpoints" / "latest.json").read_text())["path"] == "iter-000002"
    assert not (run_dir / "checkpoints" / "iter-000001").exists()  # keep: 1
    assert is_rllib_run(run_dir)

    policy = RllibPolicy.load(run_dir)
    assert [p.name for p in load_run_policies(run_dir.parent)] == [policy.name]  # experiment dir: seed-*/
    obs = np.zeros(policy.module.observation_space.shape, np.float32)
    action = policy.act(obs, {})
    assert action.shape == (3,) and np.all(np.abs(action) <= 1.0)
    np.testing.assert_array_equal(action, policy.act(obs, {}))  # deterministic
    res = evaluate_policy(policy, tiny_scenarios[:1], policy.env_id, policy.env_config, progress=False)
    (episode,) = res["episodes"]
    assert episode["steps"] >= 1 and np.isfinite(episode["reward"])
    # the evaluation command takes RLlib runs like SB3 ones: same episode, same reward
    (combined,) = evaluate_targets([str(run_dir.parent)], tiny_scenarios[:1], progress=False)
    assert combined["summary"]["seeds"] == 1
    assert combined["episodes"][0]["reward"] == episode["reward"]
