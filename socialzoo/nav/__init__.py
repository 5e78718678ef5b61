"""Navigation: the navigation graph and A*, the distance field, sight and visibility, the local planner and its arcs,
recovery, and the four sub-policies. Above maps; numpy, scipy and numba only."""
