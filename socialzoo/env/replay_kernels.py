"""The compiled loops of socialzoo.env.replay.ReplayRunner: loading a recording into a row, who is in each slot,
people entering, placing and reacting, and the measures against the recording."""

# Each loops over the rows' slots in compiled code and computes every value as the numpy expressions it replaced
# did (same operations in the same order, fastmath off), so rollouts are the same bit for bit; a step of a sparse
# recorded scene was mostly those expressions' temporaries (benchmarks/recorded_throughput.py).

from __future__ import annotations

import numpy as np

from socialzoo.core.jit import kernel
from socialzoo.scenarios.recorded_people import NEVER

# An unused occupant entry: never entering, route indices 0, speed 1 m/s (ReplayRunner's fill too).
UNUSED_OCCUPANT = (("entry", NEVER), ("exit", NEVER), ("first", 0), ("last", 0), ("occupant_speed", 1.0))
_UNUSED_SPEED = UNUSED_OCCUPANT[4][1]


@kernel
def load_row(
    row, tracks, velocities, route_frames, entry, exit_, first, last, speed, shared, follow, robot_track,
    kind, part_follows, part_reacts, part_model, replay,
    out_tracks, out_vel, out_route_frame, out_entry, out_exit, out_first, out_last, out_speed, out_shared,
    out_follows, out_reacts, out_then, out_robot_track,
):  # fmt: skip
    """ReplayRunner.reset's load of one recording (RecordedPeople's arrays, its Occupants') into
    row `row`: its n slots' tracks, velocities, route frames (padded by repeating the last),
    occupants and ways of walking (kind: each slot's part of the people spec, -1 the last entry of
    the part arrays), the replaced person's path; the row's other slots empty. Only the recording's
    block of the tracks is written (ReplayRunner.people_count, frame_count)."""
    n, frames = tracks.shape[0], tracks.shape[1]
    width, most = route_frames.shape[1], entry.shape[1]
    for f in range(frames):
        for s in range(n):
            for c in range(2):
                out_tracks[row, f, s, c] = tracks[s, f, c]
                out_vel[row, f, s, c] = velocities[s, f, c]
    for s in range(out_route_frame.shape[1]):
        mine = s < n
        for k in range(out_route_frame.shape[2]):
            out_route_frame[row, s, k] = route_frames[s, min(k, width - 1)] if mine else 0
        for k in range(out_entry.shape[2]):  # unused entries: UNUSED_OCCUPANT's fills
            held = mine and k < most
            out_entry[row, s, k] = entry[s, k] if held else NEVER
            out_exit[row, s, k] = exit_[s, k] if held else NEVER
            out_first[row, s, k] = first[s, k] if held else 0
            out_last[row, s, k] = last[s, k] if held else 0
            out_speed[row, s, k] = speed[s, k] if held else _UNUSED_SPEED
        if mine:
            part = kind[s]
            out_shared[row, s] = shared[s]
            out_follows[row, s] = follow[s] or part_follows[part]
            out_reacts[row, s] = part_reacts[part] and not follow[s]
            out_then[row, s] = replay if follow[s] else part_model[part]
        else:
            out_shared[row, s] = False
            out_follows[row, s] = False
            out_reacts[row, s] = False
            out_then[row, s] = 0
    for k in range(out_robot_track.shape[1]):
        for c in range(2):
            out_robot_track[row, k, c] = robot_track[k, c] if k < robot_track.shape[0] else 0.0


@kernel
def begin_episodes(
    rows, follows, replay, occupant, on_track, gone, reacted_at, exit_at, walked, recorded_left, recorded_exit,
    rest, elapsed, folded, deviation, moves, walked_into, contact, model,
):  # fmt: skip
    """ReplayRunner.reset's start of `rows`' episodes, once their recordings are loaded: nobody in
    a slot yet, nothing measured, and the slots that follow their tracks walked by `replay`."""
    for j in range(rows.shape[0]):
        r = rows[j]
        elapsed[r] = 0.0
        for c in range(folded.shape[1]):
            folded[r, c] = 0.0
        for k in range(deviation.shape[1]):
            deviation[r, k] = 0.0
            moves[r, k] = 0
            walked_into[r, k] = 0
            for s in range(contact.shape[2]):
                contact[r, k, s] = False
        for s in range(occupant.shape[1]):
            occupant[r, s] = -1
            on_track[r, s] = False
            gone[r, s] = False
            reacted_at[r, s] = np.nan
            exit_at[r, s] = np.nan
            walked[r, s] = 0.0
            recorded_left[r, s] = 0.0
            recorded_exit[r, s] = 0.0
            rest[r, s] = 0.0
            if follows[r, s]:
                model[r, s] = replay


@kernel
def occupants_now(rows, step_count, dt, frame_dt, on_frame, entry, occupant, t, i0, w, now, new):
    """For `rows` at their time t = steps * dt (n,): the frame i0 (n,) each is on (frame period
    frame_dt, past its recording's end too; a time within on_frame frames of a frame is on it) and the weight w (n,)
    of the next frame (0 on a frame); now (n, H), who is in each slot on frame i0 (entries at or
    before it, minus one; -1 nobody yet); new (n, H), a person other than the slot's occupant. True
    if anyone is new."""
    any_new = False
    for j in range(rows.shape[0]):
        r = rows[j]
        t[j] = step_count[r] * dt
        frame = t[j] / frame_dt[r]
        i0[j] = int(np.floor(frame + on_frame))
        w[j] = frame - i0[j] if frame - i0[j] > on_frame else 0.0
        for s in range(entry.shape[1]):
            count = 0
            for k in range(entry.shape[2]):
                if entry[r, s, k] <= i0[j]:
                    count += 1
            now[j, s] = count - 1
            new[j, s] = count > 0 and count - 1 != occupant[r, s]
            any_new = any_new or new[j, s]
    return any_new


@kernel
def enter_people(
    rows, new, now, t, follows, then, shared, first, last, occupant_speed, replay,
    occupant, on_track, gone, reacted_at, exit_at, walked, recorded_exit, recorded_left, rest, folded,
    model, route_len, waypoint, direction, pref_speed,
):  # fmt: skip
    """ReplayRunner._enter in place, slot by slot in row-major order (the order the folded sums
    add in): a reacting person leaving its slot adds one, its time lost (to its exit, or to now if
    it had not left) and its extra distance (with the straight way left if it had not left) to
    its row's `folded`; the slot's new person follows its track (REPLAY) or walks by its model
    from its route's second point, a shared slot's person along its own part at its own speed."""
    for j in range(rows.shape[0]):
        r = rows[j]
        for s in range(new.shape[1]):
            if not new[j, s]:
                continue
            if reacted_at[r, s] == reacted_at[r, s]:  # not NaN: it reacted
                cut = exit_at[r, s] != exit_at[r, s]
                folded[r, 0] += 1.0
                folded[r, 1] += (t[j] if cut else exit_at[r, s]) - recorded_exit[r, s]
                folded[r, 2] += walked[r, s] + (rest[r, s] if cut else 0.0) - recorded_left[r, s]
            k = now[j, s]
            occupant[r, s] = k
            on_track[r, s] = follows[r, s]
            gone[r, s] = False
            reacted_at[r, s] = np.nan
            exit_at[r, s] = np.nan
            walked[r, s] = 0.0
            model[r, s] = replay if follows[r, s] else then[r, s]
            if shared[r, s]:
                route_len[r, s] = last[r, s, k] + 1
                waypoint[r, s] = min(first[r, s, k] + 1, last[r, s, k])
                pref_speed[r, s] = occupant_speed[r, s, k]
            else:
                waypoint[r, s] = min(1, route_len[r, s] - 1)
            direction[r, s] = 1


@kernel
def place_people(
    rows, i0, w, t, now, new, tracks, track_vel, people_count, frame_count, on_track, gone, exit_at, direction,
    pos, vel, mask,
):  # fmt: skip
    """ReplayRunner._place's update of `rows` in place: followers where their tracks are, present
    while recorded; people a model walks enter on their track and leave where their route ends.
    A row's tracks beyond its recording (people_count slots, frame_count frames) are NaN (absent)
    with velocity 0, whatever the arrays hold there."""
    for j in range(rows.shape[0]):
        r = rows[j]
        # A row's own recording's frames only: a frame the row does not have is absent (a wider
        # recording in another row does not keep this row's people on its last frame).
        a, b = i0[j], i0[j] + 1
        on_frame = w[j] == 0.0
        for s in range(tracks.shape[2]):
            x0 = y0 = x1 = y1 = np.nan
            vx = vy = 0.0
            if s < people_count[r] and a < frame_count[r]:
                x0, y0 = tracks[r, a, s, 0], tracks[r, a, s, 1]
                vx, vy = track_vel[r, a, s, 0], track_vel[r, a, s, 1]
            if s < people_count[r] and b < frame_count[r]:
                x1, y1 = tracks[r, b, s, 0], tracks[r, b, s, 1]
            present = not np.isnan(x0) and (on_frame or not np.isnan(x1))
            if on_frame:
                x, y = x0, y0
            else:
                x, y = x0 + w[j] * (x1 - x0), y0 + w[j] * (y1 - y0)
            seen = now[j, s] >= 0
            if on_track[r, s]:
                if present:
                    pos[r, s, 0], pos[r, s, 1] = x, y
                    vel[r, s, 0], vel[r, s, 1] = vx, vy
                mask[r, s] = present
                if seen and not present and np.isnan(exit_at[r, s]):
                    exit_at[r, s] = t[j]
                continue
            if new[j, s]:
                pos[r, s, 0], pos[r, s, 1] = x, y
                vel[r, s, 0], vel[r, s, 1] = vx, vy
            walking = seen and not gone[r, s]
            leaving = walking and direction[r, s] < 0
            if leaving:
                gone[r, s] = True
                if np.isnan(exit_at[r, s]):
                    exit_at[r, s] = t[j]
            mask[r, s] = walking and not leaving


@kernel
def reacting_people(
    rows, reacts, on_track, mask, occupant, robot_pose, human_pos, human_vel, robot_vel, radius2, react_time,
    collision2, react,
):  # fmt: skip
    """Fill react (n, H): the hybrid people of `rows` on their track whom a robot's centre is within
    the reaction radius of, or would meet (centres within the collision distance) within react_time
    keeping both velocities (the point of closest approach, its time clipped to [0, react_time]);
    True if any."""
    any_react = False
    for j in range(rows.shape[0]):
        r = rows[j]
        for s in range(mask.shape[1]):
            react[j, s] = False
            if not (reacts[r, s] and on_track[r, s] and mask[r, s] and occupant[r, s] >= 0):
                continue
            for q in range(robot_pose.shape[1]):
                dx, dy = robot_pose[r, q, 0] - human_pos[r, s, 0], robot_pose[r, q, 1] - human_pos[r, s, 1]
                vx, vy = robot_vel[r, q, 0] - human_vel[r, s, 0], robot_vel[r, q, 1] - human_vel[r, s, 1]
                when = -(dx * vx + dy * vy) / max(vx * vx + vy * vy, 1e-12)
                when = min(max(when, 0.0), react_time)
                cx, cy = dx + when * vx, dy + when * vy
                if dx * dx + dy * dy < radius2 or cx * cx + cy * cy < collision2:
                    react[j, s] = True
            any_react = any_react or react[j, s]
    return any_react


@kernel
def leave_tracks(
    rows, react, frame, w, step_count, dt, frame_dt, then, occupant, first, last, route_frame, shared, exit_,
    tracks, on_track, model, route_len, waypoint, direction, reacted_at, recorded_exit, recorded_left,
):  # fmt: skip
    """ReplayRunner._react's switch of the people in react (n, H) off their tracks, in place: each walks by
    its model towards the first point of its route (of its own part, in a shared slot) recorded after
    `frame` (n,), the frame its row is on; its reaction time, its recorded exit time and the recorded
    distance left are kept: from where it is (w (n,) of the way from `frame` to the next) along its
    track to its last frame, adding the segments whose both frames are recorded, in frame order."""
    for j in range(rows.shape[0]):
        r = rows[j]
        for s in range(react.shape[1]):
            if not react[j, s]:
                continue
            on_track[r, s] = False
            model[r, s] = then[r, s]
            k = occupant[r, s]
            ahead = 0
            for p in range(route_frame.shape[2]):
                if route_frame[r, s, p] <= frame[j]:
                    ahead += 1
            if shared[r, s]:
                low, end = first[r, s, k], last[r, s, k]
            else:
                low, end = 0, route_len[r, s] - 1
            waypoint[r, s] = min(max(ahead, low), end)
            direction[r, s] = 1
            reacted_at[r, s] = step_count[r] * dt
            exit_frame = exit_[r, s, k]
            recorded_exit[r, s] = exit_frame * frame_dt[r]
            left = 0.0
            for f in range(frame[j], exit_frame):
                dx, dy = (
                    tracks[r, f + 1, s, 0] - tracks[r, f, s, 0],
                    tracks[r, f + 1, s, 1] - tracks[r, f, s, 1],
                )
                length = np.sqrt(dx * dx + dy * dy)
                if not np.isnan(length):
                    left += (1.0 - w[j]) * length if f == frame[j] else length
            recorded_left[r, s] = left


@kernel
def account_people(
    rows, reacted_at, gone, mask_before, pos_before, pos_after, route, route_len, walked, rest
):
    """ReplayRunner.account's measures of the reacting people of `rows` in place (when any row has
    one): the distance each walked in the step (not one who entered during it: its slot's position
    before the step was its previous occupant's), and the straight way left to its route's end (0
    for everyone else)."""
    off_track = False
    for j in range(rows.shape[0]):
        for s in range(gone.shape[1]):
            off_track = off_track or (
                reacted_at[rows[j], s] == reacted_at[rows[j], s] and not gone[rows[j], s]
            )
    if not off_track:
        return
    for j in range(rows.shape[0]):
        r = rows[j]
        for s in range(gone.shape[1]):
            if not (reacted_at[r, s] == reacted_at[r, s] and not gone[r, s]):  # NaN: not reacting
                rest[r, s] = 0.0
                continue
            if mask_before[r, s]:
                dx, dy = pos_after[r, s, 0] - pos_before[r, s, 0], pos_after[r, s, 1] - pos_before[r, s, 1]
                walked[r, s] += np.sqrt(dx * dx + dy * dy)
            end = route_len[r, s] - 1
            ex, ey = route[r, s, end, 0] - pos_after[r, s, 0], route[r, s, end, 1] - pos_after[r, s, 1]
            rest[r, s] = np.sqrt(ex * ex + ey * ey)


@kernel
def account_robots(
    rows, live, robot_pose, human_pos, human_vel, human_mask, robot_vel, robot_track, robot_track_len,
    collision2, deviation, moves, contact, walked_into,
):  # fmt: skip
    """ReplayRunner.account's robot measures of `rows` in place (live (n, R): the robot's episode
    had not ended): the distance to the recorded person's path (its polyline of robot_track_len
    points), the moves counted, and the people who walked into a robot (the onset of a contact at
    which the person moved towards the robot faster than the robot towards it)."""
    for j in range(rows.shape[0]):
        r = rows[j]
        points = robot_track_len[r]
        for q in range(robot_pose.shape[1]):
            px, py = robot_pose[r, q, 0], robot_pose[r, q, 1]
            if live[j, q]:
                if points > 1:
                    # The least squared distance, one square root: sqrt is monotone, so this is
                    # the least of the segments' distances exactly.
                    nearest2 = np.inf
                    for k in range(points - 1):
                        ax, ay = robot_track[r, k, 0], robot_track[r, k, 1]
                        abx, aby = robot_track[r, k + 1, 0] - ax, robot_track[r, k + 1, 1] - ay
                        u = ((px - ax) * abx + (py - ay) * aby) / max(abx * abx + aby * aby, 1e-12)
                        u = min(max(u, 0.0), 1.0)
                        cx, cy = ax + u * abx - px, ay + u * aby - py
                        nearest2 = min(nearest2, cx * cx + cy * cy)
                    deviation[r, q] += np.sqrt(nearest2)
                moves[r, q] += 1
            for s in range(human_pos.shape[1]):
                dx, dy = human_pos[r, s, 0] - px, human_pos[r, s, 1] - py
                dist2 = dx * dx + dy * dy
                close = dist2 < collision2 and human_mask[r, s]
                if close and not contact[r, q, s] and live[j, q]:
                    norm = max(np.sqrt(dist2), 1e-9)
                    ux, uy = dx / norm, dy / norm
                    person_in = -(human_vel[r, s, 0] * ux + human_vel[r, s, 1] * uy)
                    robot_in = robot_vel[r, q, 0] * ux + robot_vel[r, q, 1] * uy
                    if person_in > robot_in:
                        walked_into[r, q] += 1
                contact[r, q, s] = close


@kernel
def reacting_totals(
    rows, reacted_at, exit_at, rest, elapsed, occupant, occupant_speed, recorded_exit, walked, recorded_left,
    folded, totals,
):  # fmt: skip
    """ReplayRunner.summaries' reacting people of `rows` into totals (n, 3): per row the count, the time
    lost and the extra distance of the reacting people who left their slot (`folded`) plus those still
    in one, in slot order: each one's time to its exit (or, not gone yet, the episode's time plus the
    straight way left at its speed) against its recorded exit, and its distance walked (plus the way
    left) against the recorded distance left."""
    for j in range(rows.shape[0]):
        r = rows[j]
        count, lost, extra = 0, 0.0, 0.0
        for s in range(reacted_at.shape[1]):
            if reacted_at[r, s] != reacted_at[r, s]:  # NaN: it did not react
                continue
            done = exit_at[r, s] == exit_at[r, s]
            speed = max(occupant_speed[r, s, max(occupant[r, s], 0)], 1e-9)
            at = exit_at[r, s] if done else elapsed[r] + rest[r, s] / speed
            lost += at - recorded_exit[r, s]
            extra += walked[r, s] + (0.0 if done else rest[r, s]) - recorded_left[r, s]
            count += 1
        totals[j, 0] = folded[r, 0] + count
        totals[j, 1] = folded[r, 1] + lost
        totals[j, 2] = folded[r, 2] + extra
