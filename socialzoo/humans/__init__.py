"""Pedestrians: the crowd models (social force, walking groups, ORCA), which one drives each person (people specs),
one step of everyone, and their routes; batched over worlds and humans, numpy and numba kernels only."""
