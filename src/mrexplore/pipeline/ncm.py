"""NeuralCoMapping as a pipeline: its own candidates (frontier cells clear of obstacles pooled to nodes, one
node per cluster) and the window its planner reads distances in."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mrexplore.global_planning.ncm_nodes import in_window, ncm_frontier, pool_nodes
from mrexplore.pipeline.base import ExplorationPipeline
from mrexplore.pipeline.decision import CandidateQuery, CandidateSet
from mrexplore.preprocessing.clustering import Clusters
from mrexplore.preprocessing.denoise import denoised_frontier_cells
from mrexplore.preprocessing.frontiers import Frontiers

__all__ = ["NcmPipeline"]


@dataclass
class NcmPipeline(ExplorationPipeline):
    """NeuralCoMapping re-implemented in 2D (Ye, Dong et al., CVPR 2022): its candidates are frontier
    cells clear of obstacles pooled to 0.4 m nodes (:mod:`~mrexplore.global_planning.ncm_nodes`), one node
    per cluster; its planner (:class:`~mrexplore.training.ncm_net.NcmPlanner`) lets
    every robot pick a node; robots drive to their node. Where no frontier cell keeps clear of obstacles
    (passages under 0.4 m wide) the plain F_un cells are pooled instead."""

    def own_reads(
        self, robots_rc: NDArray[np.int32], candidates: CandidateSet, resolution_m: float
    ) -> list[NDArray[np.int32]] | None:
        """Each robot's nodes within NCM's window (:data:`~mrexplore.global_planning.ncm_nodes.WINDOW_M`);
        all nodes for a robot with none there. NCM's planner allows robot i only the nodes it reaches
        within its window (:func:`in_window`, the test its input makes), or, where it reaches none there,
        every node it reaches. A search that settles the window's nodes has their exact distances; one
        that ends without settling them has searched the robot's whole component, so every node's distance
        is exact, and ``inf`` where unreachable."""
        centres = candidates.clusters.centers_rc
        near = in_window(robots_rc, centres, resolution_m)
        return [centres[row] if row.any() else centres for row in near]

    def candidates(self, q: CandidateQuery) -> CandidateSet:
        un = np.zeros(q.state.shape, dtype=bool)
        cells = denoised_frontier_cells(q.frontiers, q.blacklist, self.preprocess.min_cluster_size)
        un[cells[:, 0], cells[:, 1]] = True
        clear = ncm_frontier(q.state, Frontiers(un, q.frontiers.occ_mask), q.resolution_m)
        nodes = pool_nodes(clear if clear.any() else un, q.resolution_m)
        labels = np.arange(len(nodes), dtype=np.int32)
        return CandidateSet(Clusters(nodes, np.ones(len(nodes), np.int32), nodes, labels))
