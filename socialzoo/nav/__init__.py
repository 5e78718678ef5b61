"""Navigation: maps, the navigation graph and A*, the local planner, the four sub-policies, scenarios.

Also the map importers, repairs and the feasibility rule for imported buildings. numpy and scipy only.
"""
