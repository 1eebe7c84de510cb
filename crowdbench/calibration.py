"""Scenario calibration: the classic robots' rows of the paper's Tables I and II under each scenario rule.

The paper's observation and reward follow CrowdNav++ and its scenario is otherwise silent, so crowdbench's circle
crossing takes CrowdNav++'s rules one by one (:data:`STEPS`, cumulative), and this module measures what each does to
the ORCA and Social Force robots — the rows a reader can check against the paper before any learning is involved.
``crowdbench calibrate`` writes ``leaderboards/calibration.json`` and the table in ``leaderboards/README.md`` is
generated from it (:func:`markdown`).
"""

from __future__ import annotations

import json
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field, replace
from typing import Any

from crowdbench.io import write_text
from crowdbench.progress import Progress

PAPER = {"orca": {"I": (97, 91, 78), "II": (93, 69, 43)}, "social_force": {"I": (65, 46, 31), "II": (60, 27, 12)}}
"""The paper's success rates [%]: Table I (ρ = 0.7 / 0.5 / 0.3, N = 20), Table II (ρ = 0, N = 10 / 20 / 30)."""
TOLERANCE = {"orca": 5, "social_force": 10}
"""How close (± percentage points) a calibrated cell should come to the paper."""


@dataclass(frozen=True)
class Scenario:
    """One calibration step: a layout with its arguments, pedestrian-model arguments and world options."""

    name: str
    layout: str = "circle_crossing"
    layout_kwargs: dict[str, Any] = field(default_factory=dict)
    model_kwargs: dict[str, Any] = field(default_factory=dict)
    world: dict[str, Any] = field(default_factory=dict)


_LEGACY_PEDS = {"safety_space": 0.0, "max_neighbors": 10}
_FIXED_SIZE = {"human_radius_range": None, "human_v_pref_range": None}
_CN_CIRCLE = {"arrival": "turn", "robot": "random", "goal_change_interval": 0.0, "goal_change_prob": 0.0}
STEPS = (
    Scenario("0 legacy: CrowdNav pedestrians, fixed crossing (0,-6)→(0,6) on the r = 6 m ring",
             "circle_crossing_legacy", {}, _LEGACY_PEDS, _FIXED_SIZE),
    Scenario("1 + pedestrian ORCA as CrowdNav++ (safety space 0.15 m, every agent a neighbour)",
             "circle_crossing_legacy", {}, {}, _FIXED_SIZE),
    Scenario("2 + robot start/goal uniform in [-6, 6]², ≥ 8 m apart", "circle_crossing_legacy", {"robot": "random"},
             {}, _FIXED_SIZE),
    Scenario("3 + pedestrians on the r = 6√2 m circle, noise ±1 m", "circle_crossing", _CN_CIRCLE, {}, _FIXED_SIZE),
    Scenario("4 + re-spawn on arrival", "circle_crossing", {**_CN_CIRCLE, "arrival": "respawn"}, {}, _FIXED_SIZE),
    Scenario("5 + random goal changes (every 5 s, p = 0.5)", "circle_crossing", {}, {}, _FIXED_SIZE),
    Scenario("6 + randomised radius U(0.3, 0.5) m and speed U(0.5, 1.5) m/s — the default", "circle_crossing"),
    Scenario("7 (not adopted) + speeds capped at 1 m/s as CrowdNav++'s ORCA walks them", "circle_crossing", {}, {},
             {"human_speed_cap": 1.0}),
)


def evaluate(scenario: Scenario, policy: str, episodes: int, seed: int = 0) -> list[dict[str, Any]]:
    """The six cells of one scenario (the leaderboard's Table I and II cells, on the scenario's layout) for one
    classic robot policy."""
    from crowdbench import leaderboard

    grid = [replace(c, layout=scenario.layout) for c in leaderboard.cells(("I", "II"))]
    rows = leaderboard.evaluate_cells(policy, grid, episodes, seed, progress=False,
                                      layout_kwargs=scenario.layout_kwargs, model_kwargs=scenario.model_kwargs,
                                      world_options=scenario.world)
    return [{"scenario": scenario.name, **r} for r in rows]


def run(episodes: int = 500, seed: int = 0, workers: int = 2, steps: tuple[Scenario, ...] = STEPS,
        progress: Progress | None = None) -> list[dict[str, Any]]:
    """Every step × {orca, social_force} × the six cells, ``workers`` processes; ``progress`` counts finished
    (step, robot) jobs. Results in step, then robot order, whatever order the jobs finish in."""
    jobs = [(s, p) for s in steps for p in ("orca", "social_force")]
    parts: list[list[dict[str, Any]]] = [[] for _ in jobs]
    with ProcessPoolExecutor(workers) as pool:
        futures = {pool.submit(evaluate, s, p, episodes, seed): k for k, (s, p) in enumerate(jobs)}
        for done, future in enumerate(as_completed(futures), 1):
            parts[futures[future]] = future.result()
            if progress is not None:
                progress.update(done)
    if progress is not None:
        progress.close()
    return [r for part in parts for r in part]


def markdown(results: list[dict[str, Any]]) -> str:
    """Success [%] per step and policy next to the paper's, cells within tolerance in bold."""
    lines = ["| step | robot | I High | I Medium | I Low | II N=10 | II N=20 | II N=30 | within ± |",
             "|---|---|---|---|---|---|---|---|---|"]
    for policy in ("orca", "social_force"):
        paper = [*PAPER[policy]["I"], *PAPER[policy]["II"]]
        lines.append(f"| paper | {policy} | " + " | ".join(str(p) for p in paper) + f" | ±{TOLERANCE[policy]} |")
    names = list(dict.fromkeys(r["scenario"] for r in results))
    for name in names:
        for policy in ("orca", "social_force"):
            rows = [r for r in results if r["scenario"] == name and r["policy"] == policy]
            if not rows:
                continue
            paper = [*PAPER[policy]["I"], *PAPER[policy]["II"]]
            cells, ok = [], 0
            for r, p in zip(rows, paper, strict=True):
                v = 100 * r["success_rate"]
                good = abs(v - p) <= TOLERANCE[policy]
                ok += good
                cells.append(f"**{v:.1f}**" if good else f"{v:.1f}")
            lines.append(f"| {name} | {policy} | " + " | ".join(cells) + f" | {ok}/6 |")
    return "\n".join(lines) + "\n"


def save(results: list[dict[str, Any]], path: str, meta: dict[str, Any]) -> None:
    write_text(path, json.dumps({"meta": meta, "results": results}, indent=2) + "\n")
