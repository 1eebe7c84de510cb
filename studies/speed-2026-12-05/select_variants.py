"""Ranking the nearest neighbours among a few candidates: ``crowdbench.spatial.select_nearest`` (strict ranks of
eight candidates at a time) against three other branch-free rankings and plain insertion, on random distances.

    PYTHONPATH=. python studies/speed-2026-12-05/select_variants.py

Per call: ``m`` candidates (random, a fresh draw each call), the 10 nearest sorted; ns per call including filling
the candidate arrays (~20 ns), best of three runs of 100,000 calls, one thread.
"""

import time

import numba as nb
import numpy as np

from crowdbench.spatial import RANK_MAX, insert_nearest, select_nearest


@nb.njit(inline="always", error_model="numpy")
def _finish(cand_d, cand_idx, m, k_max, nb_d, nb_idx, rank):
    """``select_nearest``'s ending: ranks again with the index breaking ties if two distances are equal (the ranks'
    sum says so), then each candidate to its slot (or the discard slot); returns the count."""
    total = 0
    for p in range(m):
        total += rank[p]
    if total != m * (m - 1) // 2:
        for p in range(m):
            rank[p] = 0
        for q in range(m):
            dq, iq = cand_d[q], cand_idx[q]
            for p in range(m):
                rank[p] += (dq < cand_d[p]) | ((dq == cand_d[p]) & (iq < cand_idx[p]))
    cnt = min(m, k_max)
    discard = nb_d.shape[0] - 1
    for p in range(m):
        slot = rank[p] if rank[p] < cnt else discard
        nb_d[slot], nb_idx[slot] = cand_d[p], cand_idx[p]
    return cnt


@nb.njit(inline="always", error_model="numpy")
def select_per_candidate(cand_d, cand_idx, m, k_max, nb_d, nb_idx, rank):
    """Each candidate's rank as one reduction over all candidates (vectorised over them)."""
    for p in range(m):
        dp = cand_d[p]
        r = 0
        for q in range(m):
            r += cand_d[q] < dp
        rank[p] = r
    return _finish(cand_d, cand_idx, m, k_max, nb_d, nb_idx, rank)


@nb.njit(inline="always", error_model="numpy")
def select_blocks(cand_d, cand_idx, m, k_max, nb_d, nb_idx, rank):
    """``select_nearest``'s eight-at-a-time ranks, held in array views instead of eight scalars."""
    mp = (m + 7) & ~7
    for p in range(m, mp):
        cand_d[p] = np.inf
    for p0 in range(0, mp, 8):
        d8 = cand_d[p0:p0 + 8]
        r8 = rank[p0:p0 + 8]
        for j in range(8):
            r8[j] = 0
        for q in range(m):
            dq = cand_d[q]
            for j in range(8):
                r8[j] += dq < d8[j]
    return _finish(cand_d, cand_idx, m, k_max, nb_d, nb_idx, rank)


@nb.njit(inline="always", error_model="numpy")
def select_outer(cand_d, cand_idx, m, k_max, nb_d, nb_idx, rank):
    """Candidates in the outer loop, every rank updated in the inner one (vectorised over the ranks)."""
    mp = (m + 3) & ~3
    for p in range(m, mp):
        cand_d[p] = np.inf
    for p in range(mp):
        rank[p] = 0
    for q in range(m):
        dq = cand_d[q]
        for p in range(mp):
            rank[p] += dq < cand_d[p]
    return _finish(cand_d, cand_idx, m, k_max, nb_d, nb_idx, rank)


@nb.njit
def bench(D, k, mode):
    reps, m = D.shape
    cand_d = np.empty(m + 8)
    cand_idx = np.empty(m + 8, np.int64)
    nb_d = np.empty(m + 1)
    nb_idx = np.empty(m + 1, np.int64)
    rank = np.empty(RANK_MAX, np.int64)
    s = 0
    for r in range(reps):
        for p in range(m):
            cand_d[p] = D[r, p]
            cand_idx[p] = p
        if mode == 0:
            c = select_nearest(cand_d, cand_idx, m, k, nb_d, nb_idx, rank)
        elif mode == 1:
            c = select_per_candidate(cand_d, cand_idx, m, k, nb_d, nb_idx, rank)
        elif mode == 2:
            c = select_blocks(cand_d, cand_idx, m, k, nb_d, nb_idx, rank)
        elif mode == 3:
            c = select_outer(cand_d, cand_idx, m, k, nb_d, nb_idx, rank)
        else:
            c = 0
            for p in range(m):
                c = insert_nearest(nb_d, nb_idx, c, k, cand_d[p], cand_idx[p])
        s += nb_idx[0] + nb_idx[c - 1]
    return s


NAMES = ("select_nearest (8 at a time)", "per candidate (reduction)", "8 in block arrays", "candidates outer",
         "insertion")


def main() -> None:
    rng = np.random.default_rng(0)
    print("| m | " + " | ".join(NAMES) + " |")
    print("|---:|" + "---:|" * len(NAMES))
    for m in (9, 19, 40, 64):
        D = rng.uniform(0, 100, (100_000, m))
        row, check = [], set()
        for mode in range(len(NAMES)):
            bench(D[:10], 10, mode)
            best = 1e9
            for _ in range(3):
                t = time.perf_counter()
                check.add(bench(D, 10, mode))
                best = min(best, (time.perf_counter() - t) / len(D) * 1e9)
            row.append(f"{best:.0f}")
        assert len(check) == 1, "the rankings disagree"
        print(f"| {m} | " + " | ".join(row) + " |", flush=True)


if __name__ == "__main__":
    main()
