"""The batched world's lowest layer: state arrays, geometry, walls, robot kinematics, laser, configs.

numpy (and numba kernels) only; every other subpackage builds on it.
"""
