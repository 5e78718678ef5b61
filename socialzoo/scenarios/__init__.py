"""Scenarios: who starts and ends where on a map, drawn reproducibly from a seed; the scenario
families and their registry, CrowdNav's circle- and square-crossing cases, the feasibility rule
and the map check over the scenarios a map yields. Above maps and navigation.
"""
