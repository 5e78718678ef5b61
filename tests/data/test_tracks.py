"""The track file reader (socialzoo.data.tracks) on small synthetic files in both layouts: the frame
grid, gap interpolation and splitting, every malformed file a TrackFileError naming file and line,
the NaN-padded grid, and join."""

import pickle

import numpy as np
import pytest

from socialzoo.data import Recording, Track, TrackFileError, join, read_tracks
from socialzoo.data.tracks import MAX_GAP_FRAMES


def _write(tmp_path, rows, name="scene.txt", sep="\t"):
    path = tmp_path / name
    path.write_text("".join(sep.join(str(v) for v in row) + "\n" for row in rows))
    return path


def _obsmat_row(frame, person, x, y):
    return [
        f"{float(frame):.7e}",
        f"{float(person):.7e}",
        f"{x:.7e}",
        "0.0000000e+00",
        f"{y:.7e}",
        "0",
        "0",
        "0",
    ]


# Two people, frame numbers stepping 10 as in Trajectron++'s files; person 2 starts later.
TRAJECTRON_ROWS = [
    [780, 1.0, 8.46, 3.59],
    [790, 1.0, 9.57, 3.79],
    [800, 1.0, 10.67, 3.99],
    [800, 2.0, 13.64, 5.8],
    [810, 1.0, 11.73, 4.32],
    [810, 2.0, 12.09, 5.75],
]


def test_trajectron_layout_on_its_grid(tmp_path):
    rec = read_tracks(_write(tmp_path, TRAJECTRON_ROWS))
    assert (rec.name, rec.dt, rec.num_frames) == ("scene", 0.4, 4)
    assert rec.source == str(tmp_path / "scene.txt")
    one, two = rec.tracks
    assert (one.person, one.first_frame, one.last_frame) == (1, 0, 3)
    assert (two.person, two.first_frame, two.last_frame) == (2, 2, 3)
    np.testing.assert_array_equal(one.positions, [[8.46, 3.59], [9.57, 3.79], [10.67, 3.99], [11.73, 4.32]])
    assert one.positions.dtype == np.float64 and not one.positions.flags.writeable


def test_whitespace_separated_with_blank_and_comment_lines(tmp_path):
    path = tmp_path / "spaces.txt"
    path.write_text("# frame person x y\n\n0 7 1.0 2.0\n  10   7  1.5 2.5  \n\n")
    rec = read_tracks(path, dt=0.1, name="mine")
    assert (rec.name, rec.dt, rec.num_frames, len(rec.tracks)) == ("mine", 0.1, 2, 1)
    np.testing.assert_array_equal(rec.tracks[0].positions, [[1.0, 2.0], [1.5, 2.5]])


def test_a_byte_order_mark_is_not_part_of_the_first_frame(tmp_path):
    # Editors and spreadsheets on Windows save UTF-8 with a BOM; it used to read as the first
    # line's frame ("frame is not a number: '\\ufeff0'").
    path = tmp_path / "bom.txt"
    path.write_bytes(b"\xef\xbb\xbf0\t7\t1.0\t2.0\r\n10\t7\t1.5\t2.5\r\n")
    rec = read_tracks(path)
    np.testing.assert_array_equal(rec.tracks[0].positions, [[1.0, 2.0], [1.5, 2.5]])


def test_obsmat_layout_reads_x_and_y_from_columns_2_and_4(tmp_path):
    rows = [_obsmat_row(f, 1, 0.5 * k, 2.0 + k) for k, f in enumerate((780, 786, 792))]
    rows.append(_obsmat_row(792, 2, -1.0, -2.0))
    path = _write(tmp_path, rows, "obsmat.txt", sep="   ")
    for layout in ("auto", "obsmat"):
        rec = read_tracks(path, layout=layout)
        assert rec.dt == 0.4 and rec.num_frames == 3  # frame numbers step 6 = one 0.4 s grid step
        np.testing.assert_allclose(rec.tracks[0].positions, [[0, 2], [0.5, 3], [1, 4]])
        assert (rec.tracks[1].person, rec.tracks[1].first_frame) == (2, 2)


def test_annotation_restarting_on_another_phase_after_a_pause(tmp_path):
    # As in ETH's seq_eth obsmat.txt: rows step 6 frame numbers, and after a pause with nobody
    # annotated the frames continue on another remainder modulo 6 (here 0, then 3, then 5).
    rows = [_obsmat_row(f, 1, f / 2, 0.0) for f in (780, 786, 792)]
    rows += [_obsmat_row(f, 2, f / 2, 1.0) for f in (831, 837)]  # 39 after 792: 6.5 steps
    rows += [_obsmat_row(f, 3, f / 2, 2.0) for f in (863, 869)]  # 26 after 837: 4.33 steps
    rec = read_tracks(_write(tmp_path, rows, "obsmat.txt", sep=" "))
    _, two, three = rec.tracks
    # Each stretch starts at the grid index nearest its first frame's ((f - 780) / 6, halves up)
    # and keeps its own steps; positions are the file's.
    assert [(t.person, t.first_frame, t.last_frame) for t in rec.tracks] == [
        (1, 0, 2),
        (2, 9, 10),
        (3, 14, 15),
    ]
    assert rec.num_frames == 16
    np.testing.assert_array_equal(two.positions, [[415.5, 1.0], [418.5, 1.0]])
    np.testing.assert_array_equal(three.positions, [[431.5, 2.0], [434.5, 2.0]])
    # Inside a stretch (no pause longer than a step) a frame on another remainder is refused.
    rows.insert(3, _obsmat_row(795, 4, 0.0, 0.0))
    with pytest.raises(
        TrackFileError, match=r"line 4: frame 795 is off the frame grid: frames 780 \+ k \* 6"
    ):
        read_tracks(_write(tmp_path, rows, "bad.txt", sep=" "))


def test_tracks_sorted_by_first_frame_then_person(tmp_path):
    rows = [[0, 9, 0, 0], [10, 9, 0, 0], [10, 3, 1, 1], [10, 5, 2, 2], [20, 3, 1, 1], [20, 1, 0, 0]]
    rec = read_tracks(_write(tmp_path, rows))
    assert [(t.first_frame, t.person) for t in rec.tracks] == [(0, 9), (1, 3), (1, 5), (2, 1)]


def test_short_gaps_interpolated_long_gaps_split(tmp_path):
    # Person 1 misses frames 1 and 2 (MAX_GAP_FRAMES): filled on the line. Person 2 misses 3 frames
    # after frame 1: two tracks. Person 3 keeps the grid going on every frame.
    assert MAX_GAP_FRAMES == 2
    rows = [[10 * f, 3, f, 0] for f in range(8)]
    rows += [[0, 1, 0.0, 0.0], [30, 1, 3.0, 6.0], [40, 1, 4.0, 8.0]]
    rows += [[0, 2, 0, 0], [10, 2, 1, 1], [50, 2, 5, 5], [60, 2, 6, 6]]
    rec = read_tracks(_write(tmp_path, rows))
    by_person = {}
    for t in rec.tracks:
        by_person.setdefault(t.person, []).append(t)
    (one,) = by_person[1]
    assert (one.first_frame, one.last_frame) == (0, 4)
    np.testing.assert_allclose(one.positions, [[0, 0], [1, 2], [2, 4], [3, 6], [4, 8]])
    early, late = by_person[2]
    assert (early.first_frame, early.last_frame, late.first_frame, late.last_frame) == (0, 1, 5, 6)


def test_grid_pads_absent_people_with_nan(tmp_path):
    rec = read_tracks(_write(tmp_path, TRAJECTRON_ROWS))
    grid = rec.grid()
    assert grid.shape == (2, 4, 2)
    np.testing.assert_array_equal(grid[0], rec.tracks[0].positions)
    assert np.isnan(grid[1, :2]).all() and np.isfinite(grid[1, 2:]).all()
    part = rec.grid([1], first=1, last=2)
    assert part.shape == (1, 2, 2)
    assert np.isnan(part[0, 0]).all()
    np.testing.assert_array_equal(part[0, 1], [13.64, 5.8])
    assert rec.grid([], first=0, last=0).shape == (0, 1, 2)
    with pytest.raises(ValueError, match=r"frames 2\.\.1"):
        rec.grid(first=2, last=1)
    with pytest.raises(ValueError, match=r"frames 0\.\.4 .* 0\.\.3"):
        rec.grid(last=4)
    with pytest.raises(IndexError, match="track index 2"):
        rec.grid([2])


def test_join_shifts_frames_and_person_ids(tmp_path):
    a = read_tracks(_write(tmp_path, TRAJECTRON_ROWS, "a.txt"))
    b = read_tracks(_write(tmp_path, [[0, 1, 0, 0], [10, 1, 1, 1], [0, 5, 2, 2]], "b.txt"))
    c = read_tracks(_write(tmp_path, [[0, 100, 0, 0]], "c.txt"))
    rec = join([a, b, c], "both", gap_frames=3)
    # a: frames 0..3; b: 4 + 3 = 7..8; c: 9 + 3 = 12
    assert (rec.name, rec.dt, rec.num_frames) == ("both", 0.4, 13)
    assert rec.source == f"{tmp_path / 'a.txt'} + {tmp_path / 'b.txt'} + {tmp_path / 'c.txt'}"
    assert [(t.person, t.first_frame, t.last_frame) for t in rec.tracks] == [
        (1, 0, 3),
        (2, 2, 3),
        (3, 7, 8),  # b's ids 1 and 5 collide with a's: shifted by 2 to start above a's largest, 2
        (7, 7, 7),
        (100, 12, 12),  # above every earlier id: kept
    ]
    np.testing.assert_array_equal(rec.tracks[2].positions, b.tracks[0].positions)
    assert len({t.person for t in rec.tracks}) == 5
    assert join([a], "same").num_frames == a.num_frames


def test_join_refuses_bad_arguments(tmp_path):
    a = read_tracks(_write(tmp_path, TRAJECTRON_ROWS))
    with pytest.raises(ValueError, match="at least one recording"):
        join([], "none")
    with pytest.raises(ValueError, match="gap_frames must be an int >= 0, got -1"):
        join([a, a], "x", gap_frames=-1)
    with pytest.raises(ValueError, match="one dt"):
        join([a, read_tracks(a.source, dt=0.1)], "x")


@pytest.mark.parametrize(
    ("text", "line", "what"),
    [
        ("0\t1\t1.0\t2.0\n10\t1\t1.0\n", 2, "3 columns; the trajectron layout has 4 (frame person x y)"),
        ("0 1 1 2 3\n", 1, "5 columns; expected 4 (trajectron: frame person x y) or 8"),
        (
            "0,1,1.0,2.0\n",
            1,
            "1 columns; expected 4 (trajectron: frame person x y) or 8 (obsmat: frame person "
            "pos_x pos_z pos_y v_x v_z v_y); columns are separated by whitespace, not commas",
        ),
        (
            "0\t1\t1.0\t2.0\n10,1,1.0,2.0\n",
            2,
            "1 columns; the trajectron layout has 4 (frame person x y); "
            "columns are separated by whitespace, not commas",
        ),
        (
            "frame\tperson\tx\ty\n0\t1\t1.0\t2.0\n",
            1,
            "frame is not a number: 'frame' (a header line? start it with #)",
        ),
        ("0\t1\t1.0\t2.0\n10\t1\tabc\t2.0\n", 2, "x is not a number: 'abc'"),
        ("0\t1\t1.0\t2.0\n10\t1\t1.0\tnan\n", 2, "y must be a finite number, got 'nan'"),
        ("0\t1\t1.0\t2.0\n10\t1\tinf\t2.0\n", 2, "x must be a finite number, got 'inf'"),
        ("0\t1.5\t1.0\t2.0\n", 1, "person must be a whole number, got '1.5'"),
        ("0\t1\t1\t1\n10.5\t1\t1\t1\n", 2, "frame must be a whole number, got '10.5'"),
        # Whole numbers from 2**53 on are not all floats: two people (ids a tracker counted up to
        # 2**53 + 1) read as one, silently; a huge frame number was named as -9223372036854775808.
        (
            "0\t9007199254740992\t0\t0\n10\t9007199254740993\t5\t5\n",
            1,
            "person must be a whole number below 2**53 (9007199254740992), got '9007199254740992'",
        ),
        (
            "0\t1\t0\t0\n10\t1\t1\t0\n1e20\t2\t0\t0\n",
            3,
            "frame must be a whole number below 2**53 (9007199254740992), got '1e20'",
        ),
        (
            "0\t1\t1\t1\n10\t1\t1\t1\n10\t2\t2\t2\n10\t1\t1\t1\n",
            4,
            "a duplicate of line 2 (person 1 in frame 10)",
        ),
        ("0\t1\t1\t1\n10\t1\t1\t1\n10\t1\t3\t1\n", 3, "person 1 is twice in frame 10 (also on line 2)"),
        # people step 10 frame numbers; frame 25 is off that grid
        (
            "0\t1\t0\t0\n10\t1\t0\t0\n20\t1\t0\t0\n25\t2\t0\t0\n30\t1\t0\t0\n",
            4,
            "frame 25 is off the frame grid",
        ),
        # a stray frame 5 would make the smallest step 5, but people step 10
        (
            "0\t1\t0\t0\n5\t2\t0\t0\n10\t1\t0\t0\n20\t1\t0\t0\n",
            2,
            "frame 5 is off the frame grid: frames 0 + k * 10",
        ),
    ],
)
def test_a_malformed_file_names_file_and_line(tmp_path, text, line, what):
    path = tmp_path / "bad.txt"
    path.write_text(text)
    with pytest.raises(TrackFileError) as info:
        read_tracks(path)
    assert str(info.value).startswith(f"{path}, line {line}: {what}"), str(info.value)
    assert (info.value.path, info.value.line) == (str(path), line)


def test_wrong_columns_for_an_explicit_layout(tmp_path):
    path = _write(tmp_path, TRAJECTRON_ROWS)
    with pytest.raises(TrackFileError, match=r"line 1: 4 columns; the obsmat layout has 8"):
        read_tracks(path, layout="obsmat")
    obsmat = _write(tmp_path, [_obsmat_row(0, 1, 0, 0)], "obsmat.txt")
    with pytest.raises(TrackFileError, match=r"line 1: 8 columns; the trajectron layout has 4"):
        read_tracks(obsmat, layout="trajectron")


def test_an_empty_or_binary_file_is_named(tmp_path):
    for text in ("", "\n\n# only a comment\n"):
        path = tmp_path / "empty.txt"
        path.write_text(text)
        with pytest.raises(TrackFileError, match=f"^{path}: no data rows"):
            read_tracks(path)
    binary = tmp_path / "binary.txt"
    binary.write_bytes(b"0 1 1 1\n\xff\xfe\n")
    with pytest.raises(TrackFileError, match=f"^{binary}, line 2: not a text file"):
        read_tracks(binary)


def test_bad_arguments_and_missing_file(tmp_path):
    path = _write(tmp_path, TRAJECTRON_ROWS)
    with pytest.raises(ValueError, match="unknown track file layout 'csv'"):
        read_tracks(path, layout="csv")
    with pytest.raises(ValueError, match="dt must be a positive number of seconds, got 0"):
        read_tracks(path, dt=0)
    with pytest.raises(FileNotFoundError):
        read_tracks(tmp_path / "absent.txt")


def test_track_and_recording_check_their_fields():
    with pytest.raises(ValueError, match=r"shape \(T, 2\)"):
        Track(1, 0, np.zeros((0, 2)))
    with pytest.raises(ValueError, match="first_frame must be an int >= 0"):
        Track(1, -1, np.zeros((1, 2)))
    with pytest.raises(ValueError, match="finite"):
        Track(1, 0, [[np.nan, 0.0]])
    track = Track(1, 2, [[0.0, 0.0], [1.0, 1.0]])
    assert track.last_frame == 3
    with pytest.raises(ValueError, match="ends on frame 3, past the grid's 3 frames"):
        Recording("r", 0.4, 3, (track,), "memory")
    with pytest.raises(ValueError, match="dt must be a positive number"):
        Recording("r", 0.0, 4, (track,), "memory")


def test_the_error_pickles(tmp_path):
    error = TrackFileError(tmp_path / "f.txt", 3, "wrong")
    again = pickle.loads(pickle.dumps(error))
    assert (str(again), again.line) == (str(error), 3)
