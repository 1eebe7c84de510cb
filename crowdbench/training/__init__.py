"""Training learned robot policies on batched crowd worlds — generic, for any method.

PPO (rsl-rl-lib 5.5.1, the version pinned in ``pyproject.toml``), for methods registered in
:data:`~crowdbench.training.methods.PPO_METHODS` (every registered method with ``trainer="ppo"``):

* :mod:`.config` — :class:`TrainConfig` (frozen; every field documented);
* :mod:`.vecenv`, :mod:`.shards`, :mod:`.curriculum` — the rsl-rl ``VecEnv`` over worlds sharded into worker
  processes, the responsiveness annealing;
* :mod:`.models` — the rsl-rl adapter of a method's plain-torch actor (:mod:`crowdbench.policies.nets`) and the
  critic on its trunk;
* :mod:`.rollout` — the one rollout: the world processes act with a snapshot of the policy;
* :mod:`.ppo` — the one update: rsl-rl's ``PPO.update`` run per thread (each override of rsl-rl and why: there);
* :mod:`.threads`, :mod:`.malloc` — the update's thread pool, glibc heap settings;
* :mod:`.trainer` — the loop, checkpoints and exact resume; :mod:`.plots` — curves and run tables.

Value-based methods (CADRL, SARL: imitation of a demonstrator, then TD learning with a target network) train through
:mod:`.value`.

Nothing here is imported by ``import crowdbench``: torch and rsl-rl load when training starts.
"""
