"""Operator profiles (``torch.profiler``, self CPU time, one thread) behind the studies in this folder's README.

    PYTHONPATH=. python studies/speed-2026-12-06/profile_ops.py aig-update|aig-rollout|sarl-eval [--shapes]

``aig-update``: one PPO epoch (32 mini-batches) of AIG-GST's default recipe on a fresh run's first rollout;
``aig-rollout``: one rollout (192 worlds × 30 steps, GST predictor included); ``sarl-eval``: the shipped SARL on 50
episodes of circle crossing, N = 20, ρ = 0.5 (one batch of 50 worlds).
"""

import argparse
import tempfile
import time

import torch
from torch.profiler import ProfilerActivity, profile


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=["aig-update", "aig-rollout", "sarl-eval"])
    ap.add_argument("--shapes", action="store_true", help="group by input shapes too")
    a = ap.parse_args()
    torch.set_num_threads(1)
    if a.what == "sarl-eval":
        from crowdbench.evaluation import run_episodes
        from crowdbench.policies import make_policy
        from crowdbench.worlds import make_layout

        pol = make_policy("sarl")
        kw = dict(layout=make_layout("circle_crossing"), num_humans=20, human_model="responsive_orca",
                  human_model_kwargs={"responsiveness": 0.5}, counterfactual=False)
        run_episodes(pol, 10, seed=5, num_worlds=10, **kw)  # warm-up
        work = lambda: run_episodes(pol, 50, seed=0, num_worlds=50, **kw)  # noqa: E731
    else:
        from crowdbench.training.config import TrainConfig
        from crowdbench.training.rollout import PolicySnapshot, collect
        from crowdbench.training.trainer import Trainer

        cfg = TrainConfig.for_method("aig_gst", seed=3, env_processes=1, threads=1, iterations=1, eval_every=0)
        tr = Trainer(cfg, tempfile.mkdtemp(), quiet=True)
        alg, env = tr.alg, tr.env
        alg.train_mode()
        with torch.inference_mode():
            obs, _, _ = collect(alg, env, env.get_observations(), cfg.steps_per_env, PolicySnapshot.of(alg, tr.build))
            alg.compute_returns(obs)
        alg.num_learning_epochs = 1

        def work() -> None:
            if a.what == "aig-update":
                alg.update()
            else:
                alg.storage.clear()
                with torch.inference_mode():
                    collect(alg, env, obs, cfg.steps_per_env, PolicySnapshot.of(alg, tr.build))

    with profile(activities=[ProfilerActivity.CPU], record_shapes=a.shapes) as prof:
        t = time.process_time()
        work()
        print(f"{a.what}: {time.process_time() - t:.2f} s CPU (profiled)")
    print(prof.key_averages(group_by_input_shape=a.shapes).table(sort_by="self_cpu_time_total", row_limit=30,
                                                                 max_name_column_width=30, max_shapes_column_width=70))


if __name__ == "__main__":
    main()
