"""AIG-GST's PPO update alone: CPU seconds of one epoch (32 mini-batches of the original's recipe) on a real
rollout of a fresh run (one thread, one world process).

    PYTHONPATH=. python studies/speed-2026-12-05/aig_update_time.py [--out /tmp/aig-update]
"""

import argparse
import time

import torch

from crowdbench.training.config import TrainConfig
from crowdbench.training.rollout import PolicySnapshot, collect
from crowdbench.training.trainer import Trainer

p = argparse.ArgumentParser()
p.add_argument("--out", default="/tmp/aig-update")
a = p.parse_args()
cfg = TrainConfig.for_method("aig_gst", seed=3, env_processes=1, threads=1, iterations=1, eval_every=0)
tr = Trainer(cfg, a.out, quiet=True)
alg, env = tr.alg, tr.env
obs = env.get_observations()
alg.train_mode()
t = time.process_time()
with torch.inference_mode():
    obs, _, _ = collect(alg, env, obs, cfg.steps_per_env, PolicySnapshot.of(alg, tr.build))
    alg.compute_returns(obs)
print(f"rollout ({cfg.num_envs} worlds x {cfg.steps_per_env} steps): {time.process_time() - t:.2f} s CPU", flush=True)
alg.num_learning_epochs = 1
saved = {k: (v.clone() if torch.is_tensor(v) else v) for k, v in vars(alg.storage).items()}
for _ in range(3):
    for k, v in saved.items():  # update() clears the storage: the same rollout each time
        setattr(alg.storage, k, v.clone() if torch.is_tensor(v) else v)
    t = time.process_time()
    alg.update()
    print(f"update, 1 epoch ({cfg.mini_batches} mini-batches): {time.process_time() - t:.2f} s CPU", flush=True)
