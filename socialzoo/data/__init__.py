"""Recorded pedestrian trajectories: the reader of ETH/UCY track files (socialzoo.data.tracks) and
the fetcher of their pinned public copy into a local cache (socialzoo.data.fetch).

Recorded data never enters the repository: `socialzoo data fetch eth-ucy` downloads it (or copies
it from a local folder) into a cache outside it, checking every file's SHA-256.
"""

from socialzoo.data.tracks import Recording, Track, TrackFileError, join, read_tracks

__all__ = ["Recording", "Track", "TrackFileError", "join", "read_tracks"]
