"""Pedestrians: the crowd models (the social force, Helbing-Molnar with Moussaid's extension;
walking groups, Moussaid et al. 2010; ORCA, van den Berg et al. 2011), which model drives each
person (people specs), one step of everyone, and their routes.

Batched over worlds and humans; numpy and numba kernels only.
"""
