"""Recorded pedestrian trajectories: the reader of ETH/UCY track files (socialzoo.data.tracks) and
the fetcher of their pinned public copy into a local cache (socialzoo.data.fetch)."""

from socialzoo.data.tracks import Recording, Track, TrackFileError, join, read_tracks

__all__ = ["Recording", "Track", "TrackFileError", "join", "read_tracks"]
