"""Pedestrians: the social force model (Helbing-Molnar with Moussaid's extension) and their routes.

Batched over worlds and humans; numpy and numba kernels only.
"""
