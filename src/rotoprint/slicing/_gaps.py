"""Closing the open chains a cross-section of an open mesh leaves.

A chain of segments ends where it meets a mesh edge used by one face (a hole in the mesh),
or a non-manifold edge. Unclosed chains would make a fill rule run to the edge of the image
(a streak). Open ends are joined here, every end to a start, so that the fill never streaks:

1. pairs of an open end and an open start at most ``gap_radius_mm`` apart are joined,
   nearest first (a hole in the mesh bridged by a straight segment);
2. every chain still open is closed onto itself by a chord from its end to its start, and
   reported as *left open*, with the chord's length;
3. anything left (non-manifold tangles) is joined nearest first, and reported too.
"""

from __future__ import annotations


import numpy as np

from .._dataclass import dataclass
from ._sections import Segments


@dataclass(frozen=True)
class GapReport:
    """What closing did in one layer."""

    closed: int = 0
    closed_max_mm: float = 0.0
    left_open: int = 0
    left_open_max_mm: float = 0.0

    def to_json(self) -> dict:
        return {
            "closed": self.closed,
            "closed_max_mm": self.closed_max_mm,
            "left_open": self.left_open,
            "left_open_max_mm": self.left_open_max_mm,
        }


def _balance(seg: Segments, suspect: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Open ends and open starts: indices into the segments (end side / start side)."""
    touch_s = suspect[seg.start_edge]
    touch_e = suspect[seg.end_edge]
    if not (touch_s.any() or touch_e.any()):
        return np.empty(0, np.int64), np.empty(0, np.int64)
    s_idx = np.flatnonzero(touch_s)
    e_idx = np.flatnonzero(touch_e)
    edges = np.unique(np.concatenate([seg.start_edge[s_idx], seg.end_edge[e_idx]]))
    ns = np.zeros(len(edges), np.int64)
    ne = np.zeros(len(edges), np.int64)
    np.add.at(ns, np.searchsorted(edges, seg.start_edge[s_idx]), 1)
    np.add.at(ne, np.searchsorted(edges, seg.end_edge[e_idx]), 1)
    open_ends, open_starts = [], []
    # For each edge, the surplus ends (or starts) are open; which copies is immaterial since
    # copies on one edge share one point.
    for pos in np.flatnonzero(ne != ns):
        e = edges[pos]
        if ne[pos] > ns[pos]:
            cand = e_idx[seg.end_edge[e_idx] == e]
            open_ends.extend(cand[: ne[pos] - ns[pos]].tolist())
        else:
            cand = s_idx[seg.start_edge[s_idx] == e]
            open_starts.extend(cand[: ns[pos] - ne[pos]].tolist())
    return np.asarray(open_ends, np.int64), np.asarray(open_starts, np.int64)


def _chains(seg: Segments) -> np.ndarray:
    """Chain label per segment: segments linked end-to-start through a shared mesh edge."""
    nodes, inv = np.unique(np.concatenate([seg.start_edge, seg.end_edge]), return_inverse=True)
    from ._kernels import union_labels as _union_labels  # numba: loaded only for open meshes

    n = len(seg)
    return _union_labels(inv[:n].astype(np.int64), inv[n:].astype(np.int64), len(nodes))


def close_gaps(seg: Segments, suspect_edge: np.ndarray, gap_radius_mm: float) -> tuple[Segments, GapReport]:
    """Add joining segments so that every chain of ``seg`` is closed (see module doc)."""
    ends, starts = _balance(seg, suspect_edge)
    if len(ends) == 0 and len(starts) == 0:
        return seg, GapReport()
    pe = seg.end[ends]
    ps = seg.start[starts]
    chain = _chains(seg)
    ce, cs = chain[ends], chain[starts]
    d = np.linalg.norm(pe[:, None, :] - ps[None, :, :], axis=2) if len(ends) and len(starts) else np.zeros((len(ends), len(starts)))
    used_e = np.zeros(len(ends), bool)
    used_s = np.zeros(len(starts), bool)
    joins: list[tuple[int, int]] = []
    closed_len: list[float] = []
    open_len: list[float] = []

    def greedy(mask: np.ndarray, out: list[float]) -> None:
        ii, jj = np.nonzero(mask)
        for k in np.argsort(d[ii, jj], kind="stable"):
            i, j = ii[k], jj[k]
            if not used_e[i] and not used_s[j]:
                used_e[i] = used_s[j] = True
                joins.append((i, j))
                out.append(float(d[i, j]))

    if d.size:
        greedy(d <= gap_radius_mm, closed_len)
        # Chains are relabelled by the joins made so far before closing them onto themselves.
        label = np.arange(chain.max() + 1)
        for i, j in joins:
            a, b = label[ce[i]], label[cs[j]]
            label[label == b] = a
        greedy((label[ce][:, None] == label[cs][None, :]) & ~used_e[:, None] & ~used_s[None, :], open_len)
        greedy(~used_e[:, None] & ~used_s[None, :], open_len)
    if joins:
        ji = np.array([i for i, _ in joins])
        jj = np.array([j for _, j in joins])
        add_start, add_end = pe[ji], ps[jj]
        seg = Segments(
            start=np.concatenate([seg.start, add_start]),
            end=np.concatenate([seg.end, add_end]),
            start_edge=np.concatenate([seg.start_edge, np.full(len(ji), -1)]),
            end_edge=np.concatenate([seg.end_edge, np.full(len(ji), -1)]),
        )
    report = GapReport(
        closed=len(closed_len),
        closed_max_mm=max(closed_len, default=0.0),
        left_open=len(open_len),
        left_open_max_mm=max(open_len, default=0.0),
    )
    return seg, report
