"""Far distances on a graph of sector portals, kept where the map changes (hierarchical path-finding).

Late in a mission on a whole building, a robot's far distances came from a search over every passable block
of the floor (:mod:`~mrexplore.paths.far_field`): on a KTH floor at 0.05 m about 250,000 blocks of 0.15 m
a robot, eight searches a decision, half the decision. The floor changes only where the robots' scans fell.

So the block grid is cut into sectors of ``S`` x ``S`` blocks, as in hierarchical pathfinding (Botea,
Müller and Schaeffer 2004, HPA*). Where two side-by-side sectors meet, each run of passable block pairs
across their border is an entrance. Each entrance gets portals: one pair of blocks facing each other, at
the middle of an entrance of up to ``spacing`` blocks, and at the middles of equal parts of a longer one,
so a straight way across an open hall bends by at most a few blocks at a border. A portal's block is a
node; nodes in one sector are joined by their distance inside the sector, nodes facing each other across
a border by one block. A decision searches this graph (a few nodes per sector instead of ``S * S``
blocks) from the nodes that the blocks the robot's exact search reached reach inside their sectors,
and reads a block's distance as the best over its sector's nodes (and the robot's own seed blocks
there) plus the way inside the sector, searched for the sectors read only.

:class:`PortalGraph` keeps the nodes, the distances inside each sector and the edges across borders from
decision to decision, and redoes them only for the sectors whose blocks changed and those neighbours
whose portals moved. Every distance it gives is the length of a real path of whole blocks, so never shorter than the
block search's; it is longer where the shortest way crosses a border off a portal.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba as nb
import numpy as np
from numpy.typing import NDArray

from mrexplore.paths.kernels import descend_to_seed, seeded_search, start_values

__all__ = ["PortalField", "PortalGraph"]


@nb.njit(cache=True, nogil=True)
def _border(
    G: np.ndarray, r: int, c: int, dr: int, dc: int, orr: int, occ: int, S: int, K: int, out: np.ndarray, n: int
) -> int:  # pragma: no cover - numba
    """Append to ``out[n:]`` this sector's portal blocks on one border: blocks ``(r + t dr, c + t dc)`` for
    ``t < S``, each facing ``(+orr, +occ)``. Both sectors of a border walk it in the same direction, so they
    place the same portals. Returns the new count (a block already listed, a corner, is not repeated)."""
    t = 0
    while t < S:
        if not (G[r + t * dr, c + t * dc] and G[r + t * dr + orr, c + t * dc + occ]):
            t += 1
            continue
        a = t
        while t < S and G[r + t * dr, c + t * dc] and G[r + t * dr + orr, c + t * dc + occ]:
            t += 1
        length = t - a
        m = 1 if length <= K else (length + K - 1) // K
        for i in range(m):
            p = a + ((2 * i + 1) * length) // (2 * m)
            rr, cc = r + p * dr, c + p * dc
            seen = False
            for j in range(n):
                if out[j, 0] == rr and out[j, 1] == cc:
                    seen = True
            if not seen:
                out[n, 0] = rr
                out[n, 1] = cc
                n += 1
    return n


@nb.njit(cache=True, nogil=True)
def _sector_nodes(G: np.ndarray, si: int, sj: int, S: int, K: int, out: np.ndarray) -> int:  # pragma: no cover
    """The portal blocks of sector ``(si, sj)`` into ``out`` (global block rows and columns); their count."""
    H, W = G.shape
    R, C = si * S, sj * S
    n = 0
    if R > 0:
        n = _border(G, R, C, 0, 1, -1, 0, S, K, out, n)
    if R + S < H:
        n = _border(G, R + S - 1, C, 0, 1, 1, 0, S, K, out, n)
    if C > 0:
        n = _border(G, R, C, 1, 0, 0, -1, S, K, out, n)
    if C + S < W:
        n = _border(G, R, C + S - 1, 1, 0, 0, 1, S, K, out, n)
    return n


@nb.njit(cache=True, nogil=True)
def _refresh(  # noqa: C901 - numba kernel
    G: np.ndarray,
    S: int,
    K: int,
    dirty: np.ndarray,
    changed: np.ndarray,
    n_nodes: np.ndarray,
    nodes: np.ndarray,
    intra: np.ndarray,
    inter: np.ndarray,
    node_at: np.ndarray,
    longest: np.ndarray,
) -> None:  # pragma: no cover - numba
    """Bring the ``dirty`` sectors (those whose blocks ``changed``, by sector, and their neighbours) up to
    date: their nodes; the distances between the nodes inside the sector (``intra``; ``longest``, the
    longest of them) where the blocks changed or the nodes moved; and the edges across borders
    (``inter``) round every sector whose nodes moved. A neighbour's nodes move only where the changed
    sector's blocks on their common border did, so most neighbours keep their ways."""
    nsw = G.shape[1] // S
    n_slots = n_nodes.shape[0]
    max_nodes = nodes.shape[1]
    Wp = S + 2
    fresh = np.zeros((dirty.shape[0], max_nodes, 2), dtype=nodes.dtype)
    counts = np.zeros(dirty.shape[0], dtype=np.int64)
    moved = np.zeros(n_slots, dtype=np.bool_)
    for i in range(dirty.shape[0]):
        slot = dirty[i]
        n = _sector_nodes(G, slot // nsw, slot % nsw, S, K, fresh[i])
        counts[i] = n
        if n != n_nodes[slot]:
            moved[slot] = True
        else:
            for k in range(n):
                if fresh[i, k, 0] != nodes[slot, k, 0] or fresh[i, k, 1] != nodes[slot, k, 1]:
                    moved[slot] = True
        if moved[slot]:
            for k in range(n_nodes[slot]):
                node_at[nodes[slot, k, 0], nodes[slot, k, 1]] = -1
    for i in range(dirty.shape[0]):
        slot = dirty[i]
        if moved[slot]:
            n_nodes[slot] = counts[i]
            for k in range(counts[i]):
                nodes[slot, k, 0] = fresh[i, k, 0]
                nodes[slot, k, 1] = fresh[i, k, 1]
                node_at[nodes[slot, k, 0], nodes[slot, k, 1]] = slot * max_nodes + k
    cap = S * S + 1
    q_node = np.empty((2, cap), dtype=np.int32)
    q_key = np.empty((2, cap), dtype=np.float32)
    seed = np.zeros(1, dtype=np.int64)
    key = np.zeros(1, dtype=np.float32)
    for slot in dirty:
        if not (moved[slot] or changed[slot]):
            continue
        n = n_nodes[slot]
        longest[slot] = 0.0
        if n == 0:
            continue
        br0, bc0 = (slot // nsw) * S, (slot % nsw) * S
        start = start_values(G[br0 : br0 + S, bc0 : bc0 + S])
        for k in range(n):
            seed[0] = (nodes[slot, k, 0] - br0 + 1) * Wp + nodes[slot, k, 1] - bc0 + 1
            best = seeded_search(start, Wp, seed, key, q_node, q_key)
            for j in range(n):
                d = best[(nodes[slot, j, 0] - br0 + 1) * Wp + nodes[slot, j, 1] - bc0 + 1]
                intra[slot, k, j] = d
                if d < np.inf and d > longest[slot]:
                    longest[slot] = d
    mark = np.zeros(n_slots, dtype=np.bool_)
    for slot in dirty:
        if not moved[slot]:
            continue
        mark[slot] = True
        si, sj = slot // nsw, slot % nsw
        if si > 0:
            mark[slot - nsw] = True
        if slot + nsw < n_slots:
            mark[slot + nsw] = True
        if sj > 0:
            mark[slot - 1] = True
        if sj + 1 < nsw:
            mark[slot + 1] = True
    H, W = G.shape
    for slot in range(n_slots):
        if not mark[slot]:
            continue
        for k in range(n_nodes[slot]):
            r, c = nodes[slot, k, 0], nodes[slot, k, 1]
            for t, (dr, dc) in enumerate(((-1, 0), (1, 0), (0, -1), (0, 1))):
                rr, cc = r + dr, c + dc
                inter[slot, k, t] = -1
                if 0 <= rr < H and 0 <= cc < W and (rr // S != r // S or cc // S != c // S):
                    inter[slot, k, t] = node_at[rr, cc]


@nb.njit(cache=True, nogil=True)
def _compact(
    n_nodes: np.ndarray, intra: np.ndarray, inter: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover - numba
    """The graph's nodes numbered ``0 .. n - 1`` and its edges in rows (compressed sparse rows), what a
    search reads: ``compact`` (the number of each node id, ``-1`` for none), ``node_of`` (the id of each
    number), ``indptr``, ``adj`` and ``wt`` (each number's edges, ``adj[indptr[i] : indptr[i + 1]]``, their
    lengths in blocks)."""
    max_nodes = intra.shape[1]
    N = n_nodes.shape[0] * max_nodes
    compact = np.full(N, -1, dtype=np.int64)
    n = 0
    for slot in range(n_nodes.shape[0]):
        n += n_nodes[slot]
    node_of = np.empty(n, dtype=np.int64)
    i = 0
    edges = 0
    for slot in range(n_nodes.shape[0]):
        for k in range(n_nodes[slot]):
            compact[slot * max_nodes + k] = i
            node_of[i] = slot * max_nodes + k
            i += 1
            edges += n_nodes[slot] + 4
    indptr = np.zeros(n + 1, dtype=np.int64)
    adj = np.empty(edges, dtype=np.int64)
    wt = np.empty(edges, dtype=np.float32)
    e = 0
    for i in range(n):
        u = node_of[i]
        slot, k = u // max_nodes, u % max_nodes
        for j in range(n_nodes[slot]):
            w = intra[slot, k, j]
            if j != k and w < np.inf:
                adj[e] = compact[slot * max_nodes + j]
                wt[e] = w
                e += 1
        for t in range(4):
            v = inter[slot, k, t]
            if v >= 0:
                adj[e] = compact[v]
                wt[e] = 1.0
                e += 1
        indptr[i + 1] = e
    return compact, node_of, indptr, adj[:e].copy(), wt[:e].copy()


@nb.njit(cache=True, nogil=True)
def _graph_search(
    indptr: np.ndarray,
    adj: np.ndarray,
    wt: np.ndarray,
    longest_edge: float,
    seeds: np.ndarray,
    seed_keys: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - numba
    """Dijkstra over the portal graph (:func:`_compact`'s rows) from nodes ``seeds`` at ``seed_keys``
    (blocks): each node's distance (``inf`` where unreached) and the node it was reached from (``-1`` for
    a seed and unreached).

    Every edge is at least one block long (two distinct blocks, or a step across a border), so the queue
    is one of buckets a block wide (Dial's): a key relaxed from bucket ``b`` lands in ``b + 1`` or later,
    so every key in a bucket is final when the bucket is reached, in whatever order it is popped. No edge
    is longer than ``longest_edge`` (a way inside one sector), so the buckets are a ring of more than
    that. Every array is sized up front: growing one inside the loop made numba count references at every
    step (8 ms a search late on a KTH floor; 1.6 ms with the arrays sized, on the sectors' own tables;
    on these rows, less)."""
    n = indptr.shape[0] - 1
    dist = np.full(n, np.inf, dtype=np.float32)
    parent = np.full(n, -1, dtype=np.int64)
    done = np.zeros(n, dtype=np.bool_)
    cap = seeds.shape[0] + adj.shape[0] + 1  # every edge improves its end at most once
    ring = 1
    longest = longest_edge
    for i in range(seed_keys.shape[0]):
        longest = max(longest, float(seed_keys[i]))
    while ring <= longest + 2:
        ring *= 2
    head = np.full(ring, -1, dtype=np.int64)
    e_node = np.empty(cap, dtype=np.int64)
    e_next = np.empty(cap, dtype=np.int64)
    n_entries = 0
    live = 0
    for i in range(seeds.shape[0]):
        u = seeds[i]
        if seed_keys[i] < dist[u]:
            dist[u] = seed_keys[i]
            b = int(seed_keys[i]) % ring
            e_node[n_entries] = u
            e_next[n_entries] = head[b]
            head[b] = n_entries
            n_entries += 1
            live += 1
    b = 0
    while live > 0:
        e = head[b % ring]
        if e < 0:
            b += 1
            continue
        head[b % ring] = e_next[e]
        live -= 1
        u = e_node[e]
        du = dist[u]
        if done[u] or int(du) != b:
            continue  # settled already, or stale: settled from a lower bucket
        done[u] = True
        for j in range(indptr[u], indptr[u + 1]):
            v = adj[j]
            nd = du + wt[j]
            if nd < dist[v]:
                dist[v] = nd
                parent[v] = u
                nb_ = int(nd) % ring
                e_node[n_entries] = v
                e_next[n_entries] = head[nb_]
                head[nb_] = n_entries
                n_entries += 1
                live += 1
    return dist, parent


@nb.njit(cache=True, nogil=True)
def _fill(
    G: np.ndarray,
    S: int,
    slot: int,
    nodes: np.ndarray,
    n_nodes: np.ndarray,
    slot_dist: np.ndarray,
    extra_cells: np.ndarray,
    extra_keys: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - numba
    """``(S, S) float32`` distances (blocks) to every block of sector ``slot``: the best over its nodes of
    the node's distance (``slot_dist``, by the node's place in the sector) and over the source's own seed
    blocks in it (``extra_cells``, ``a S + b`` inside the sector, at ``extra_keys``) plus the way inside the
    sector; and ``(S, S) float32`` each seed's own distance at its block (``inf`` elsewhere), what a path
    is read back to."""
    nsw = G.shape[1] // S
    br0, bc0 = (slot // nsw) * S, (slot % nsw) * S
    Wp = S + 2
    n = n_nodes[slot]
    e = extra_cells.shape[0]
    keys = np.empty(n + e, dtype=np.float32)
    cells = np.empty(n + e, dtype=np.int64)
    seed_key = np.full((S, S), np.inf, dtype=np.float32)
    m = 0
    for k in range(n):
        d = slot_dist[k]
        if d < np.inf:
            a, b = nodes[slot, k, 0] - br0, nodes[slot, k, 1] - bc0
            keys[m] = d
            cells[m] = (a + 1) * Wp + b + 1
            seed_key[a, b] = d
            m += 1
    for i in range(e):
        a, b = extra_cells[i] // S, extra_cells[i] % S
        keys[m] = extra_keys[i]
        cells[m] = (a + 1) * Wp + b + 1
        seed_key[a, b] = min(seed_key[a, b], extra_keys[i])
        m += 1
    order = np.argsort(keys[:m], kind="mergesort")
    q_node = np.empty((2, S * S + 1), dtype=np.int32)
    q_key = np.empty((2, S * S + 1), dtype=np.float32)
    start = start_values(G[br0 : br0 + S, bc0 : bc0 + S])
    best = seeded_search(start, Wp, cells[:m][order], keys[:m][order], q_node, q_key)
    return best.reshape((S + 2, Wp))[1:-1, 1:-1].copy(), seed_key


@nb.njit(cache=True, nogil=True)
def _fill_many(
    G: np.ndarray,
    S: int,
    slots: np.ndarray,
    nodes: np.ndarray,
    n_nodes: np.ndarray,
    dist: np.ndarray,
    ex_first: np.ndarray,
    ex_cells: np.ndarray,
    ex_keys: np.ndarray,
    store: np.ndarray,
    at: int,
) -> None:  # pragma: no cover - numba
    """:func:`_fill` for each of ``slots`` into ``store[at], store[at + 1], ...``; a sector's own seeds are
    ``ex_cells[ex_first[slot] : ex_first[slot + 1]]`` (at ``ex_keys``)."""
    m = nodes.shape[1]
    for i in range(slots.shape[0]):
        slot = slots[i]
        a, b = ex_first[slot], ex_first[slot + 1]
        own = dist[slot * m : (slot + 1) * m]
        store[at + i] = _fill(G, S, slot, nodes, n_nodes, own, ex_cells[a:b], ex_keys[a:b])[0]


@nb.njit(cache=True, nogil=True)
def _node_seeds(
    G: np.ndarray,
    S: int,
    nodes: np.ndarray,
    n_nodes: np.ndarray,
    ex_first: np.ndarray,
    ex_cells: np.ndarray,
    ex_keys: np.ndarray,
    slots: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - numba
    """The nodes of ``slots`` the source's own seed blocks reach inside their sector, and their distances
    there: where the graph search starts (node ids, keys in blocks)."""
    m = nodes.shape[1]
    none = np.full(m, np.inf, dtype=np.float32)
    total = 0
    for slot in slots:
        total += n_nodes[slot]
    ids = np.empty(total, dtype=np.int64)
    keys = np.empty(total, dtype=np.float32)
    nsw = G.shape[1] // S
    j = 0
    for slot in slots:
        a, b = ex_first[slot], ex_first[slot + 1]
        field = _fill(G, S, slot, nodes, n_nodes, none, ex_cells[a:b], ex_keys[a:b])[0]
        br0, bc0 = (slot // nsw) * S, (slot % nsw) * S
        for k in range(n_nodes[slot]):
            d = field[nodes[slot, k, 0] - br0, nodes[slot, k, 1] - bc0]
            if d < np.inf:
                ids[j] = slot * m + k
                keys[j] = d
                j += 1
    return ids[:j], keys[:j]


@nb.njit(cache=True, nogil=True)
def _room(out: np.ndarray, n: int, k: int) -> np.ndarray:  # pragma: no cover - numba
    """``out`` (rows of blocks, the first ``n`` in use) with room for ``k`` more: itself, or a copy twice
    as large as needed."""
    if n + k <= out.shape[0]:
        return out
    grown = np.empty((2 * (n + k), 2), dtype=np.int64)
    grown[:n] = out[:n]
    return grown


@nb.njit(cache=True, nogil=True)
def _chain(
    G: np.ndarray, S: int, nodes: np.ndarray, n_nodes: np.ndarray, parent: np.ndarray, u: int
) -> tuple[np.ndarray, int]:  # pragma: no cover - numba
    """The blocks from node ``u`` back along ``parent`` to the node with none (``u`` left out): across a
    border the facing block, inside a sector the shortest way there; and that last node. One compiled
    loop: the same in Python took milliseconds a path late on a KTH floor with 16 robots."""
    m = nodes.shape[1]
    nsw = G.shape[1] // S
    out = np.empty((256, 2), dtype=np.int64)
    n = 0
    none_cells = np.zeros(0, dtype=np.int64)
    none_keys = np.zeros(0, dtype=np.float32)
    for _ in range(parent.shape[0]):
        p = parent[u]
        if p < 0:
            break
        slot = u // m
        if p // m == slot:
            only = np.full(m, np.inf, dtype=np.float32)
            only[p % m] = 0.0
            f, key = _fill(G, S, slot, nodes, n_nodes, only, none_cells, none_keys)
            br0, bc0 = (slot // nsw) * S, (slot % nsw) * S
            way = descend_to_seed(
                f, G[br0 : br0 + S, bc0 : bc0 + S], key, nodes[slot, u % m, 0] - br0, nodes[slot, u % m, 1] - bc0
            )
            k = way.shape[0] - 1
            out = _room(out, n, k)
            for i in range(k):
                out[n + i, 0] = way[i + 1, 0] + br0
                out[n + i, 1] = way[i + 1, 1] + bc0
            n += k
        else:
            out = _room(out, n, 1)
            out[n, 0] = nodes[p // m, p % m, 0]
            out[n, 1] = nodes[p // m, p % m, 1]
            n += 1
        u = p
    return out[:n].copy(), u


class PortalGraph:
    """The portal graph of one map's block grid, kept from decision to decision (module docstring).

    Parameters
    ----------
    shape_blocks:
        ``(rows, cols)`` of the whole map in blocks (block ``(i, j)`` covers fine rows ``i f ...``).
    sector_blocks:
        ``S``, a sector's side in blocks, >= 2.
    spacing_blocks:
        An entrance longer than this gets more than one portal, >= 1.
    """

    def __init__(self, shape_blocks: tuple[int, int], sector_blocks: int, spacing_blocks: int) -> None:
        if sector_blocks < 2:
            raise ValueError(f"sector_blocks must be >= 2, got {sector_blocks}")
        if spacing_blocks < 1:
            raise ValueError(f"spacing_blocks must be >= 1, got {spacing_blocks}")
        S, K = sector_blocks, spacing_blocks
        self.S, self.K = S, K
        self.nsh, self.nsw = -(-shape_blocks[0] // S), -(-shape_blocks[1] // S)
        self.grid = np.zeros((self.nsh * S, self.nsw * S), dtype=np.bool_)
        # Per border at most S / K portals plus one per run of passable pairs (a run ends at a blocked pair).
        max_nodes = 4 * (S // K + 1 + (S + 1) // 2)
        n_slots = self.nsh * self.nsw
        self.n_nodes = np.zeros(n_slots, dtype=np.int64)
        self.nodes = np.zeros((n_slots, max_nodes, 2), dtype=np.int64)
        self.intra = np.full((n_slots, max_nodes, max_nodes), np.inf, dtype=np.float32)
        self.inter = np.full((n_slots, max_nodes, 4), -1, dtype=np.int64)
        self.node_at = np.full(self.grid.shape, -1, dtype=np.int64)
        self.longest = np.zeros(n_slots, dtype=np.float32)
        """Per sector, the longest way between two of its nodes (blocks)."""
        self._rows = _compact(self.n_nodes, self.intra, self.inter)
        """:func:`_compact` of the graph as it stands."""

    @property
    def max_nodes(self) -> int:
        return int(self.nodes.shape[1])

    def refresh(self, pooled: NDArray[np.bool_], br0: int, bc0: int) -> None:
        """Bring the graph to ``pooled`` ``(h, w) bool`` passable blocks, whose block ``(0, 0)`` is the map's
        block ``(br0, bc0)`` (multiples of the sector side); outside it nothing is passable."""
        if br0 % self.S or bc0 % self.S:
            raise ValueError(f"pooled blocks must start on a sector corner, got ({br0}, {bc0}) for sectors of {self.S}")
        new = np.zeros_like(self.grid)
        h, w = pooled.shape
        new[br0 : br0 + h, bc0 : bc0 + w] = pooled[: new.shape[0] - br0, : new.shape[1] - bc0]
        S = self.S
        changed = (new != self.grid).reshape(self.nsh, S, self.nsw, S).any(axis=(1, 3))
        grown = changed.copy()
        grown[1:] |= changed[:-1]
        grown[:-1] |= changed[1:]
        grown[:, 1:] |= changed[:, :-1]
        grown[:, :-1] |= changed[:, 1:]
        dirty = np.flatnonzero(grown.ravel())
        self.grid = new
        if len(dirty):
            _refresh(
                new,
                S,
                self.K,
                dirty,
                changed.ravel(),
                self.n_nodes,
                self.nodes,
                self.intra,
                self.inter,
                self.node_at,
                self.longest,
            )
            self._rows = _compact(self.n_nodes, self.intra, self.inter)

    def search(self, seed_ids: NDArray[np.int64], seed_keys: NDArray[np.floating]) -> PortalField:
        """Distances from nodes ``seed_ids`` at ``seed_keys`` (blocks) over the graph."""
        dist, parent = self._search(np.asarray(seed_ids, np.int64), np.asarray(seed_keys, np.float32))
        none = _SectorSeeds(np.zeros(self.nsh * self.nsw + 1, np.int64), np.zeros(0, np.int64), np.zeros(0, np.float32))
        return PortalField(self, dist, parent, none)

    def _search(
        self, ids: NDArray[np.int64], keys: NDArray[np.float32]
    ) -> tuple[NDArray[np.float32], NDArray[np.int64]]:
        """Distances and the node each was reached from, by node id (``inf`` and ``-1`` where unreached)."""
        compact, node_of, indptr, adj, wt = self._rows
        d, p = _graph_search(indptr, adj, wt, float(self.longest.max()), compact[ids], keys)
        dist = np.full(len(compact), np.inf, dtype=np.float32)
        parent = np.full(len(compact), -1, dtype=np.int64)
        dist[node_of] = d
        reached = p >= 0
        parent[node_of[reached]] = node_of[p[reached]]
        return dist, parent

    def search_from(self, blocks: NDArray[np.integer], keys: NDArray[np.floating]) -> PortalField:
        """Distances from seed blocks ``(k, 2)`` of the map at ``keys`` (blocks), e.g. the blocks a robot's
        exact search reaches: the nodes each sector's seeds reach inside it start the graph search, and
        a block of a seeded sector reads the seeds' own ways inside it too (as a search over the blocks
        from the same seeds would, where those ways pass no portal)."""
        b = np.asarray(blocks, np.int64).reshape(-1, 2)
        k = np.asarray(keys, np.float32).reshape(-1)
        S = self.S
        slot = (b[:, 0] // S) * self.nsw + b[:, 1] // S
        order = np.argsort(slot, kind="stable")
        slot, b, k = slot[order], b[order], k[order]
        first = np.searchsorted(slot, np.arange(self.nsh * self.nsw + 1)).astype(np.int64)
        seeds = _SectorSeeds(first, ((b[:, 0] % S) * S + b[:, 1] % S).astype(np.int64), k)
        ids, node_keys = _node_seeds(self.grid, S, self.nodes, self.n_nodes, *seeds, np.unique(slot))
        dist, parent = self._search(ids, node_keys)
        return PortalField(self, dist, parent, seeds)


class _SectorSeeds(NamedTuple):
    """A source's own seed blocks by sector: those of sector ``s`` are ``cells[first[s] : first[s + 1]]``
    (``a S + b`` inside the sector) at ``keys`` (blocks)."""

    first: NDArray[np.int64]
    cells: NDArray[np.int64]
    keys: NDArray[np.float32]


class PortalField:
    """One source's distances over a :class:`PortalGraph`: at its nodes, and at any block, in blocks."""

    def __init__(
        self, graph: PortalGraph, dist: NDArray[np.float32], parent: NDArray[np.int64], seeds: _SectorSeeds
    ) -> None:
        self.graph, self.dist, self.parent = graph, dist, parent
        self.seeds = seeds
        self._where = np.full(graph.nsh * graph.nsw, -1, dtype=np.int64)
        """Per sector, its place in :attr:`_store` (``-1``: not searched yet)."""
        self._store = np.empty((0, graph.S, graph.S), dtype=np.float32)
        self._stored = 0

    def values(self, blocks: NDArray[np.integer]) -> NDArray[np.float64]:
        """``(k,) float64`` distances (blocks) at ``(k, 2)`` blocks of the map; ``inf`` where unreached or
        not passable. Each sector read is searched once per field."""
        g = self.graph
        b = np.asarray(blocks, np.int64).reshape(-1, 2)
        out = np.full(len(b), np.inf)
        ok = (b[:, 0] >= 0) & (b[:, 0] < g.grid.shape[0]) & (b[:, 1] >= 0) & (b[:, 1] < g.grid.shape[1])
        if not ok.any():
            return out
        r, c = b[ok, 0], b[ok, 1]
        slots = (r // g.S) * g.nsw + c // g.S
        missing = slots[self._where[slots] < 0]
        if len(missing):
            missing = np.unique(missing)
            need = self._stored + len(missing)
            if need > len(self._store):
                grown = np.empty((max(need, 2 * len(self._store)), g.S, g.S), dtype=np.float32)
                grown[: self._stored] = self._store[: self._stored]
                self._store = grown
            _fill_many(g.grid, g.S, missing, g.nodes, g.n_nodes, self.dist, *self.seeds, self._store, self._stored)
            self._where[missing] = np.arange(self._stored, need)
            self._stored = need
        out[ok] = self._store[self._where[slots], r % g.S, c % g.S]
        return out

    def _own(self, slot: int) -> tuple[NDArray[np.int64], NDArray[np.float32]]:
        """The source's own seed blocks in sector ``slot`` and their keys."""
        a, b = int(self.seeds.first[slot]), int(self.seeds.first[slot + 1])
        return self.seeds.cells[a:b], self.seeds.keys[a:b]

    def corridor(self, block: tuple[int, int]) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """A shortest way from ``block`` back to a seed, as ``(k, 2) int64`` blocks (``block`` first: down its
        sector to the first node or seed, along the graph's way back, each step inside a sector as its
        shortest way there, and inside the last sector to the source's own seed block), and that seed block
        ``(2,) int64``; empty and ``(-1, -1)`` where ``block`` is unreached."""
        g = self.graph
        S, m = g.S, g.max_nodes
        r, c = block
        slot = (r // S) * g.nsw + c // S
        at_nodes = self.dist[slot * m : (slot + 1) * m]
        field, seed_key = _fill(g.grid, S, slot, g.nodes, g.n_nodes, at_nodes, *self._own(slot))
        if not math.isfinite(float(field[r % S, c % S])):
            return np.zeros((0, 2), np.int64), np.array([-1, -1], np.int64)
        br0, bc0 = (slot // g.nsw) * S, (slot % g.nsw) * S
        passable = g.grid[br0 : br0 + S, bc0 : bc0 + S]
        down = descend_to_seed(field, passable, seed_key, r - br0, c - bc0).astype(np.int64) + np.array([br0, bc0])
        u = int(g.node_at[int(down[-1, 0]), int(down[-1, 1])])
        if u < 0 or not self.dist[u] <= seed_key[down[-1, 0] - br0, down[-1, 1] - bc0]:
            return down, down[-1]  # down to one of the source's own seed blocks
        ways, root = _chain(g.grid, S, g.nodes, g.n_nodes, self.parent, u)
        slot = root // m  # a node the source's own seeds in its sector reached (or a seed node itself)
        br0, bc0 = (slot // g.nsw) * S, (slot % g.nsw) * S
        f, key = _fill(g.grid, S, slot, g.nodes, g.n_nodes, np.full(m, np.inf, np.float32), *self._own(slot))
        ur, uc = (int(x) for x in g.nodes[slot, root % m])
        last = np.zeros((0, 2), np.int64)
        if math.isfinite(float(f[ur - br0, uc - bc0])):
            way = descend_to_seed(f, g.grid[br0 : br0 + S, bc0 : bc0 + S], key, ur - br0, uc - bc0)
            last = way[1:].astype(np.int64) + np.array([br0, bc0])
        out = np.vstack([down, ways, last])
        return out, out[-1]
