"""Maps: the map file (walls, navigation graph, legal poses) and its checks, floor-plan importers, and the tools that
complete and repair a map (occupancy grid, roadmap, legal poses); numpy and scipy only, below nav and scenarios."""
