"""Data and training for the learned predictor: ``crowdbench predictor record`` then ``crowdbench predictor train``.

**Data** (:func:`record`): crowdbench's own crowds, nothing downloaded — circle crossing with latent-responsive ORCA
pedestrians (10–30, ρ ~ U(0, 0.8) drawn per episode, the range H²INT's curriculum covers) around an ORCA robot
(CrowdNav++'s ``collect_data.py`` records ORCA humans around an invisible ORCA robot). Every ``stride`` steps of every
world the robot's :class:`~crowdbench.predictors.base.Track` — the same code the observation uses, so training sees
exactly what the robot will see, partial detection and re-spawns included — gives one scene: the ``T`` observed
positions of the pedestrians in view now (relative to the robot's current position) and their true positions over
the next ``K`` steps, kept only while they stay in the episode and do not re-spawn.

**Training** (:func:`train`): Gaussian negative log-likelihood, Adam 1e-3, step decay ×0.3 at 25 / 50 / 75 % of the
epochs, batches of 64 scenes (CrowdNav++'s GST recipe with fewer epochs); the last 10 % of the recorded worlds are
held out. The checkpoint records ADE / FDE [m] on them next to constant velocity's.
"""

from __future__ import annotations

import json
import os
import sys
import time
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from crowdbench.predictors.base import HORIZON, MAX_STEP, OBSERVED, Track, constant_velocity


@dataclass(frozen=True)
class RecordConfig:
    """What :func:`record` runs."""

    worlds: int = 32
    """Worlds stepped at once (each its own episodes) [-]."""
    steps: int = 2000
    """Steps per world [-]."""
    stride: int = 4
    """Steps between recorded scenes [-]."""
    seed: int = 0
    """Seeds the worlds' episodes and the ρ draws."""
    humans_range: tuple[int, int] = (10, 30)
    """Pedestrians per episode, drawn uniformly [-]."""
    rho_range: tuple[float, float] = (0.0, 0.8)
    """Crowd mean responsiveness per episode, uniform [-]."""


def record(cfg: RecordConfig, path: str | None = None) -> dict[str, np.ndarray]:
    """Record scenes (see the module docstring): ``pos`` ``(S, T, A, 2)`` [m], ``seen`` ``(S, T, A)``, ``future``
    ``(S, A, K, 2)`` [m], ``valid`` ``(S, A)`` (seen now and a usable future), ``world`` ``(S,)``; pedestrians seen now
    come first in each scene, ``A`` = the most seen at once. Written atomically to ``path`` (``.npz``) if given."""
    from crowdbench.config import make_config
    from crowdbench.policies.classic import ORCAPolicy
    from crowdbench.robots.observations import make_observation
    from crowdbench.worlds.world import CrowdWorld

    config = make_config(humans_range=cfg.humans_range)
    world = CrowdWorld(config, cfg.worlds, "circle_crossing", "responsive_orca")
    robot = ORCAPolicy(config)  # the ORCA robot drives while the crowd is recorded
    obs_builder = make_observation(robot.observation, config)
    rng = np.random.default_rng(cfg.seed)

    def reset(mask: np.ndarray | None) -> None:
        world.human_model.set_responsiveness(float(rng.uniform(*cfg.rho_range)))
        n = cfg.worlds if mask is None else int(mask.sum())
        world.reset(seeds=[int(s) for s in rng.integers(0, 2**63 - 1, n)], mask=mask)

    reset(None)
    H, W, T, K = world.num_humans, cfg.worlds, OBSERVED, HORIZON
    pos = np.empty((cfg.steps + 1, W, H, 2))
    steps = np.empty((cfg.steps + 1, W), np.int64)
    active = np.empty((cfg.steps + 1, W, H), bool)
    robot_pos = np.empty((cfg.steps + 1, W, 2))
    for t in range(cfg.steps + 1):
        pos[t], robot_pos[t] = world.pos[:, 1:], world.pos[:, 0]
        steps[t], active[t] = world.steps, world.active[:, 1:]
        if t < cfg.steps:
            res = world.step(robot.act(obs_builder.build(world)))
            done = res.terminated | res.truncated
            if done.any():
                reset(done)
    in_range = np.linalg.norm(pos - robot_pos[:, :, None], axis=-1) <= config.sensing_range
    track = Track(W, H, T)
    scenes: dict[str, list[np.ndarray]] = {k: [] for k in ("pos", "seen", "future", "valid", "world")}
    for t in range(cfg.steps - K + 1):
        track.update(pos[t], active[t] & in_range[t], steps[t])
        if t < T - 1 or t % cfg.stride:
            continue
        fut = pos[t + 1:t + K + 1].transpose(1, 2, 0, 3)  # (W, H, K, 2)
        same = (steps[t + 1:t + K + 1] == steps[t] + np.arange(1, K + 1)[:, None]).all(0)  # (W,)
        ahead = np.concatenate([pos[t][:, :, None], fut], axis=2)
        smooth = (np.linalg.norm(np.diff(ahead, axis=2), axis=-1) <= MAX_STEP).all(-1)  # no re-spawn ahead
        valid = track.seen[:, -1] & same[:, None] & smooth & active[t]
        origin = robot_pos[t][:, None, None, :]
        scenes["pos"].append(track.pos - origin)
        scenes["seen"].append(track.seen.copy())
        scenes["future"].append(fut - origin)
        scenes["valid"].append(valid)
        scenes["world"].append(np.arange(W))
    data = {k: np.concatenate(v) for k, v in scenes.items()}
    keep = data["valid"].any(-1)
    data = {k: v[keep] for k, v in data.items()}
    order = np.argsort(~data["valid"], axis=-1, kind="stable")  # valid pedestrians first
    A = int(data["valid"].sum(-1).max())
    order = order[:, :A]
    data["pos"] = np.take_along_axis(data["pos"], order[:, None, :, None], 2).astype(np.float32)
    data["seen"] = np.take_along_axis(data["seen"], order[:, None, :], 2)
    data["future"] = np.take_along_axis(data["future"], order[:, :, None, None], 1).astype(np.float32)
    data["valid"] = np.take_along_axis(data["valid"], order, 1)
    # a pedestrian seen now but not valid (no clean future) still informs the others: keep it present, unscored
    if path is not None:
        from crowdbench.io import atomic_path

        with atomic_path(path, suffix=".npz") as tmp, open(tmp, "wb") as f:
            from crowdbench.worlds.digest import crowd_digest

            np.savez_compressed(f, **data, config=json.dumps({**asdict(cfg), "crowd": crowd_digest()}))
    return data


def load_data(path: str) -> dict[str, np.ndarray]:
    """Scenes written by :func:`record`."""
    with np.load(path, allow_pickle=False) as f:
        return {k: f[k] for k in f.files if k != "config"}


def recorded_crowd(path: str) -> str | None:
    """The crowd digest (:func:`~crowdbench.worlds.digest.crowd_digest`) the scenes of ``path`` were recorded on;
    ``None`` for files written before it was recorded."""
    with np.load(path, allow_pickle=False) as f:
        return json.loads(str(f["config"])).get("crowd") if "config" in f.files else None


@dataclass(frozen=True)
class PredictorTrainConfig:
    """A predictor training run."""

    epochs: int = 20
    """Passes over the training scenes [-]."""
    batch_size: int = 64
    """Scenes per gradient step [-]."""
    learning_rate: float = 1e-3
    """Adam's initial learning rate, ×0.3 at 25 / 50 / 75 % of the epochs."""
    seed: int = 0
    """Seeds the initialisation and the batch order."""
    holdout: float = 0.1
    """Share of the recorded worlds held out for ADE / FDE [-]."""
    threads: int = 1
    """torch threads."""


def errors(pred: np.ndarray, future: np.ndarray, valid: np.ndarray) -> tuple[float, float]:
    """ADE and FDE [m] of predicted positions ``pred`` ``(S, A, K, 2)`` against ``future`` over the ``valid``
    ``(S, A)`` pedestrians."""
    d = np.linalg.norm(pred - future, axis=-1)[valid]  # (n, K)
    return float(d.mean()), float(d[:, -1].mean())


def predict_scenes(model, data: dict[str, np.ndarray], idx: np.ndarray) -> np.ndarray:
    """Mean predictions ``(len(idx), A, K, 2)`` [m] of ``model`` (a :class:`~crowdbench.predictors.gst.GSTModel`) for
    scenes ``idx`` of ``data``, in chunks of about 512 scenes, each cut to its most pedestrians seen now (they come
    first; the rest stay zero)."""
    import torch

    preds = []
    with torch.inference_mode():
        for chunk in np.array_split(idx, max(1, len(idx) // 512)):
            a = max(int(data["seen"][chunk, -1].sum(-1).max()), 1)
            mean = model(torch.from_numpy(data["pos"][chunk, :, :a]), torch.from_numpy(data["seen"][chunk, :, :a]))[0]
            full = np.zeros((len(chunk), data["future"].shape[1], model.cfg.horizon, 2), np.float32)
            full[:, :a] = mean.numpy()
            preds.append(full)
    return np.concatenate(preds)


def compare(data: dict[str, np.ndarray], checkpoint: str | None = None) -> dict[str, tuple[float, float]]:
    """ADE and FDE [m] of the ``gst`` predictor (``checkpoint``; default: the shipped one) and of constant velocity
    on every scene of ``data``."""
    from crowdbench.predictors.gst import load_model

    model, _ = load_model(checkpoint)
    return {"gst": errors(predict_scenes(model, data, np.arange(len(data["pos"]))), data["future"], data["valid"]),
            "const_vel": errors(constant_velocity(data["pos"], data["seen"]), data["future"], data["valid"])}


def train(data: dict[str, np.ndarray], out: str, cfg: PredictorTrainConfig, quiet: bool = False,
          crowd: str | None = None) -> dict[str, Any]:
    """Train a :class:`~crowdbench.predictors.gst.GSTModel` on recorded scenes; writes ``out/gst.pt`` (the checkpoint,
    atomically) and ``out/history.json``; returns the checkpoint's metrics. ``crowd``: the digest of the crowd the
    scenes were recorded on (:func:`recorded_crowd`), kept in the checkpoint's provenance."""
    import torch

    from crowdbench import __version__, checkpoints
    from crowdbench.io import write_text
    from crowdbench.predictors.gst import METHOD, GSTConfig, GSTModel, gaussian_nll

    torch.set_num_threads(cfg.threads)
    torch.manual_seed(cfg.seed)
    rng = np.random.default_rng(cfg.seed)
    worlds = int(data["world"].max()) + 1
    test = data["world"] >= worlds - max(1, round(cfg.holdout * worlds))
    tr = np.flatnonzero(~test)
    model = GSTModel(GSTConfig())
    opt = torch.optim.Adam(model.parameters(), lr=cfg.learning_rate)
    sched = torch.optim.lr_scheduler.MultiStepLR(
        opt, [max(1, cfg.epochs * q // 4) for q in (1, 2, 3)], gamma=0.3)
    t = {k: torch.from_numpy(v) for k, v in data.items()}

    def batch(idx: np.ndarray) -> tuple[torch.Tensor, ...]:
        a = max(int(data["seen"][idx, -1].sum(-1).max()), 1)  # seen-now pedestrians come first
        i = torch.from_numpy(idx)
        return t["pos"][i, :, :a], t["seen"][i, :, :a], t["future"][i, :a], t["valid"][i, :a]

    history: dict[str, list[float]] = {"epoch": [], "nll": [], "ade": [], "fde": [], "time": []}
    te = np.flatnonzero(test)
    t0 = time.time()
    for epoch in range(cfg.epochs):
        model.train()
        losses = []
        for idx in np.array_split(rng.permutation(tr), max(1, len(tr) // cfg.batch_size)):
            pos, seen, future, valid = batch(idx)
            mean, std, rho = model(pos, seen)
            nll = gaussian_nll(mean, std, rho, future)  # (b, a, K)
            loss = nll[valid].mean()
            opt.zero_grad(set_to_none=True)
            loss.backward()
            torch.nn.utils.clip_grad_norm_(model.parameters(), 10.0)
            opt.step()
            losses.append(loss.item())
        sched.step()
        model.eval()
        ade, fde = errors(predict_scenes(model, data, te), data["future"][te], data["valid"][te])
        for k, v in (("epoch", epoch + 1), ("nll", float(np.mean(losses))), ("ade", ade), ("fde", fde),
                     ("time", time.time() - t0)):
            history[k].append(v)
        if not quiet:
            print(f"epoch {epoch + 1}/{cfg.epochs} | nll {history['nll'][-1]:.3f} | held-out ADE {ade:.3f} m, "
                  f"FDE {fde:.3f} m | {history['time'][-1] / 60:.1f} min", file=sys.stderr, flush=True)
    cv_ade, cv_fde = errors(constant_velocity(data["pos"][te], data["seen"][te]), data["future"][te],
                            data["valid"][te])
    metrics = {"ade": history["ade"][-1], "fde": history["fde"][-1], "const_vel_ade": cv_ade,
               "const_vel_fde": cv_fde, "train_scenes": int(len(tr)), "test_scenes": int(len(te))}
    os.makedirs(out, exist_ok=True)
    ckpt = {"format": checkpoints.FORMAT, "method": METHOD, "crowdbench_version": __version__,
            "model": asdict(model.cfg), "net": model.state_dict(), "seed": cfg.seed, "epochs": cfg.epochs,
            "train_config": asdict(cfg), "crowd": crowd, **metrics}
    checkpoints.save(ckpt, os.path.join(out, "gst.pt"))
    write_text(os.path.join(out, "history.json"),
               json.dumps({"config": asdict(cfg), "history": history, **metrics}, indent=1) + "\n")
    return metrics
