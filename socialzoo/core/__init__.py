"""The batched world's lowest layer: state arrays, geometry, walls, robot kinematics, laser, configs,
and the metric registry (socialzoo.core.metrics)."""
