"""Trainers: one readable module per learning algorithm, each with a frozen dataclass of its arguments
and a `train(args)` that writes the learned policy file and the record of how it was made.
"""
