"""Maps: the map file (walls, navigation graph, legal poses) and its checks, the importers of real
floor plans, and the tools that complete and repair a map (occupancy grid, roadmap, legal poses).
numpy and scipy only; below navigation and scenarios.
"""
