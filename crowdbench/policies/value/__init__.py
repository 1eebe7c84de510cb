"""CrowdNav's value-based baselines, CADRL and SARL.

* :mod:`.model` — the value networks (:class:`CADRLNet`, :class:`SARLNet`) and their configs;
* :mod:`.lookahead` — joint states, the 81 actions, constant-velocity propagation and CrowdNav's reward, batched;
* :mod:`.policy` — the registered robot policies ``cadrl`` and ``sarl`` (greedy look-ahead on a checkpoint);
* ``checkpoints/`` — the shipped checkpoints (package data). Training: :mod:`crowdbench.training.value`.
"""

from __future__ import annotations
