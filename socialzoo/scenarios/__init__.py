"""Scenarios: who starts and ends where on a map, drawn reproducibly from a seed; the scenario families and their
registry, CrowdNav's crossing cases, the feasibility rule and the map check. Above maps and navigation."""
