"""The compiled loops of socialzoo.env.replay.ReplayRunner: starting a row's episode, who is in each slot, people
entering, placing and reacting, and the measures against the recording (read through the rows' pointers into the
socialzoo.env.recording_bank.RecordingBank: slot s of row r is the bank's slot slot_at[r] + s)."""

# Each loops over the rows' slots in compiled code and computes every value as the numpy expressions it replaced
# did (same operations in the same order, fastmath off), so rollouts are the same bit for bit; a step of a sparse
# recorded scene was mostly those expressions' temporaries (benchmarks/recorded_throughput.py).

from __future__ import annotations

import numpy as np

from socialzoo.core.jit import kernel
from socialzoo.env.crowd_outcome import closest_gap


@kernel
def begin_episodes(
    rows, kind, slot_at, people, follow, part_follows, part_reacts, part_model, replay,
    follows, reacts, then, occupant, on_track, gone, reacted_at, exit_at, walked, recorded_left, recorded_exit,
    rest, elapsed, folded, deviation, moves, walked_into, contact, model,
):  # fmt: skip
    """ReplayRunner.reset's start of `rows`' episodes, pointed at their recordings: each slot's way of
    walking (kind (n, H): its part of the people spec, -1 the last entry of the part arrays; a slot the
    recording says follows its track does, whatever the spec), nobody in a slot yet, nothing measured,
    and the slots that follow their tracks walked by `replay`. The row's slots beyond its recording's
    people neither follow nor react."""
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
            if s < people[r]:
                part, recorded = kind[j, s], follow[slot_at[r] + s]
                follows[r, s] = recorded or part_follows[part]
                reacts[r, s] = part_reacts[part] and not recorded
                then[r, s] = replay if recorded else part_model[part]
            else:
                follows[r, s] = False
                reacts[r, s] = False
                then[r, s] = 0
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
def settle_rows(
    rows, step_count, dt, frame_dt, on_frame, react, radius2, react_time, collision2, replay,
    slot_at, people, point_at, frames, occupants_at, occupants, shared, route_at, route_points, entry, exit_, first,
    last, speed, route_frame, track_pos, track_vel,
    follows, reacts, then, occupant, on_track, gone, reacted_at, exit_at, walked, recorded_exit, recorded_left, rest,
    folded, pos, vel, mask, model, route_len, waypoint, direction, pref_speed, robot_pose, robot_vel,
):  # fmt: skip
    """ReplayRunner's people of `rows` at the rows' time t = steps * dt, in place, slot by slot in row-major
    order: who is in the slot now, its new person entering, its position, velocity and presence, and with
    `react` (the robots are seen) a hybrid person a robot came near leaving its track.

    Each of those reads and writes its slot only (and its row's `folded`, whose sums add in row-major slot
    order), so this one pass computes what a pass of each over every slot did. One kernel, its parts
    inline: a compiled call per slot and part, passing it its arrays, made a step of eth at B = 256 cost seven
    times as much (860 us against 125).

    - The frame: a row is on frame i0 = floor(t / frame_dt + on_frame) (past its recording's end too; a
      time within on_frame frames of a frame is on it), w of the way to the next (0 on a frame).
    - Who is in a slot: the last of its people who entered at or before i0 (-1: nobody yet), found
      from the one in it before (a slot's people enter in order; a row's time only goes on, and
      begin_episodes empties the slots); a slot beyond the recording's people has nobody in it, ever:
      absent.
    - Entering: the one the new person follows is folded into the measures (a reacting person leaving its
      slot adds one, its time lost (to its exit, or to t if it had not left, plus the straight way left
      from there at its speed) and its extra distance (with that way left) to the row's `folded`); the new
      person follows its track (REPLAY) or walks by its model from its route's second point, a shared
      slot's person along its own part at its own speed.
    - Placing: a follower where its track is, present while recorded; a person a model walks enters on its
      track (where it was last recorded by then, when the frame after it is not: a person seen on one
      frame, or one whose whole track fell between two steps) and leaves where its route ends. A frame
      the row's own recording does not have is absent (a wider recording in another row does not keep
      this row's people on its last frame).
    - Reacting: a hybrid person on its track whom a robot's centre is within the reaction radius of, or
      would meet (centres within the collision distance) within react_time keeping both velocities (the
      point of closest approach, its time clipped to [0, react_time]), walks by its model towards the first
      point of its route (of its own part, in a shared slot) recorded after i0; its reaction time, its
      recorded exit time and the recorded distance left are kept: from where it is along its track to its
      last frame, adding the segments whose both frames are recorded, in frame order."""
    for j in range(rows.shape[0]):
        r = rows[j]
        t = step_count[r] * dt
        frame = t / frame_dt[r]
        i0 = int(np.floor(frame + on_frame))
        w = frame - i0 if frame - i0 > on_frame else 0.0
        n = people[r]
        for s in range(n):
            g = slot_at[r] + s
            # Who is in the slot now: its people enter in order and a row's time only goes on, so
            # from the one in it before (-1 at the episode's start) to the last entered by i0.
            now = occupant[r, s]
            while now + 1 < occupants[g] and entry[occupants_at[g] + now + 1] <= i0:
                now += 1
            new = now >= 0 and now != occupant[r, s]
            # Entering.
            if new:
                if reacted_at[r, s] == reacted_at[r, s]:  # not NaN: it reacted
                    cut = exit_at[r, s] != exit_at[r, s]
                    own = max(speed[occupants_at[g] + max(occupant[r, s], 0)], 1e-9)
                    folded[r, 0] += 1.0
                    folded[r, 1] += (t if cut else exit_at[r, s]) + rest[r, s] / own - recorded_exit[r, s]
                    folded[r, 2] += walked[r, s] + rest[r, s] - recorded_left[r, s]
                occupant[r, s] = now
                on_track[r, s] = follows[r, s]
                gone[r, s] = False
                reacted_at[r, s] = np.nan
                exit_at[r, s] = np.nan
                walked[r, s] = 0.0
                rest[r, s] = 0.0
                model[r, s] = replay if follows[r, s] else then[r, s]
                if shared[g]:
                    o = occupants_at[g] + now
                    route_len[r, s] = last[o] + 1
                    waypoint[r, s] = min(first[o] + 1, last[o])
                    pref_speed[r, s] = speed[o]
                else:
                    waypoint[r, s] = min(1, route_len[r, s] - 1)
                direction[r, s] = 1
            # Slots that are absent with nothing to place or react, settled as the placing below
            # settles them without reading their tracks: off its track, nobody in the slot yet or its
            # person left for good; on its track, past its person's last frame (each run of a slot's
            # recorded frames is one person: its frames are absent until the next one enters).
            if on_track[r, s]:
                if now >= 0 and exit_[occupants_at[g] + now] < i0:
                    mask[r, s] = False
                    if np.isnan(exit_at[r, s]):
                        exit_at[r, s] = t
                    continue
            elif now < 0 or (gone[r, s] and not new):
                mask[r, s] = False
                continue
            # Placing.
            x0 = y0 = x1 = y1 = np.nan
            vx = vy = 0.0
            if i0 < frames[r]:
                p = point_at[r] + i0 * n + s
                x0, y0 = track_pos[p, 0], track_pos[p, 1]
                vx, vy = track_vel[p, 0], track_vel[p, 1]
            if i0 + 1 < frames[r]:
                p = point_at[r] + (i0 + 1) * n + s
                x1, y1 = track_pos[p, 0], track_pos[p, 1]
            at_frame = w == 0.0
            present = not np.isnan(x0) and (at_frame or not np.isnan(x1))
            if at_frame:
                x, y = x0, y0
            else:
                x, y = x0 + w * (x1 - x0), y0 + w * (y1 - y0)
            seen = now >= 0
            if on_track[r, s]:
                if present:
                    pos[r, s, 0], pos[r, s, 1] = x, y
                    vel[r, s, 0], vel[r, s, 1] = vx, vy
                mask[r, s] = present
                if seen and not present and np.isnan(exit_at[r, s]):
                    exit_at[r, s] = t
            else:
                if new:
                    if not present:
                        # Its frame has no next one recorded (a person seen on one frame) or it is past its
                        # last (its whole track fell between two steps): it enters where it was last seen by
                        # then, on a recorded frame.
                        p = point_at[r] + min(i0, exit_[occupants_at[g] + now]) * n + s
                        x, y = track_pos[p, 0], track_pos[p, 1]
                        vx, vy = track_vel[p, 0], track_vel[p, 1]
                    pos[r, s, 0], pos[r, s, 1] = x, y
                    vel[r, s, 0], vel[r, s, 1] = vx, vy
                walking = seen and not gone[r, s]
                leaving = walking and direction[r, s] < 0
                if leaving:
                    gone[r, s] = True
                    if np.isnan(exit_at[r, s]):
                        exit_at[r, s] = t
                mask[r, s] = walking and not leaving
            # Reacting.
            if not (react and reacts[r, s] and on_track[r, s] and mask[r, s] and occupant[r, s] >= 0):
                continue
            near = False
            for q in range(robot_pose.shape[1]):
                dx, dy = robot_pose[r, q, 0] - pos[r, s, 0], robot_pose[r, q, 1] - pos[r, s, 1]
                ux, uy = robot_vel[r, q, 0] - vel[r, s, 0], robot_vel[r, q, 1] - vel[r, s, 1]
                when = -(dx * ux + dy * uy) / max(ux * ux + uy * uy, 1e-12)
                when = min(max(when, 0.0), react_time)
                cx, cy = dx + when * ux, dy + when * uy
                if dx * dx + dy * dy < radius2 or cx * cx + cy * cy < collision2:
                    near = True
            if not near:
                continue
            on_track[r, s] = False
            model[r, s] = then[r, s]
            o = occupants_at[g] + occupant[r, s]
            # The slot's route points recorded by i0, its own only (once all are, the count is past `end`
            # with or without a padding, so the clip below gives the same waypoint).
            ahead = 0
            for p in range(route_at[g], route_at[g] + route_points[g]):
                if route_frame[p] <= i0:
                    ahead += 1
            if shared[g]:
                low, end = first[o], last[o]
            else:
                low, end = 0, route_len[r, s] - 1
            waypoint[r, s] = min(max(ahead, low), end)
            direction[r, s] = 1
            reacted_at[r, s] = t
            exit_frame = exit_[o]
            recorded_exit[r, s] = exit_frame * frame_dt[r]
            left = 0.0
            for f in range(i0, exit_frame):
                p0, p1 = point_at[r] + f * n + s, point_at[r] + (f + 1) * n + s
                dx, dy = track_pos[p1, 0] - track_pos[p0, 0], track_pos[p1, 1] - track_pos[p0, 1]
                length = np.sqrt(dx * dx + dy * dy)
                if not np.isnan(length):
                    left += (1.0 - w) * length if f == i0 else length
            recorded_left[r, s] = left
        for s in range(n, mask.shape[1]):
            mask[r, s] = False


@kernel
def account_step(
    recorded, was_done, dt, step_count, people, elapsed, reacted_at, gone, exit_at, mask_before, pos_before,
    pos_after, route, route_len, walked, rest, robot_pose, human_vel, human_mask, robot_vel, robot_at, robot_points,
    robot_track, robot_box, chunk, collision2, deviation, moves, contact, walked_into, in_step, robot_before,
    vel_before, collision,
):  # fmt: skip
    """ReplayRunner.account in place: one step of the recorded rows whose robots' episodes had not all ended
    before it (was_done (B, R)): its time, the reacting people's measures and the robots'.

    The reacting people (when any row has one): the distance each walked in the step, and the straight way
    left to its route's end (kept once it left). A person's walk counts from the step after the one at whose
    end it reacted (in that one it walked its track, before the place its recorded distance left starts from)
    to the step it left in (its time counts to that step's end); not in a step during which it entered (its
    slot's position before the step was its previous occupant's). The robots whose episode had not ended: the
    distance to the recorded person's path (its polyline of robot_points[r] points of robot_track from
    robot_at[r], with a bounding box robot_box every `chunk` segments) and the moves counted; every robot: the
    people who walked into it (the onset of a contact at which the person moved towards the robot faster than
    the robot towards it). A contact is the world's, centres within the collision distance at the step's end
    (person and robot velocities after the step); with `in_step`, the CrowdNav task's judgement, the closest
    approach during the step from robot_before and the people's positions, velocities (vel_before) and
    presence before it, the robot at its move over dt (socialzoo.env.crowd_outcome.closest_gap with
    `collision` the distance), its onset where the relative move first came within touching, with those
    velocities. Only a row's recorded people's slots: the slots beyond are never present, never react."""
    b = recorded.shape[0]
    counted = np.zeros(b, dtype=np.bool_)
    off_track, most_points = False, 0
    for r in range(b):
        if not recorded[r]:
            continue
        for q in range(was_done.shape[1]):
            counted[r] = counted[r] or not was_done[r, q]
        if not counted[r]:
            continue
        most_points = max(most_points, robot_points[r])
        t = step_count[r] * dt  # the row's time after the step, as ReplayRunner's settle_rows takes it
        for s in range(people[r]):
            reacted = reacted_at[r, s] == reacted_at[r, s]  # not NaN
            off_track = off_track or (reacted and (not gone[r, s] or exit_at[r, s] == t))
    box_gap = np.empty(max(most_points - 2, 0) // chunk + 1)  # scratch: the most boxes of a path
    for r in range(b):
        if not counted[r]:
            continue
        elapsed[r] += dt
        if off_track:  # else nobody walks off a track: every rest stays as it is
            t = step_count[r] * dt
            for s in range(people[r]):
                reacted = reacted_at[r, s] == reacted_at[r, s]  # NaN: not reacting
                walking = reacted and not gone[r, s]
                if (
                    mask_before[r, s]
                    and reacted
                    and reacted_at[r, s] != t
                    and (walking or exit_at[r, s] == t)
                ):
                    dx, dy = (
                        pos_after[r, s, 0] - pos_before[r, s, 0],
                        pos_after[r, s, 1] - pos_before[r, s, 1],
                    )
                    walked[r, s] += np.sqrt(dx * dx + dy * dy)
                if not (walking or (reacted and exit_at[r, s] == t)):
                    continue  # one who left keeps the way left from where it left
                end = route_len[r, s] - 1
                ex, ey = route[r, s, end, 0] - pos_after[r, s, 0], route[r, s, end, 1] - pos_after[r, s, 1]
                rest[r, s] = np.sqrt(ex * ex + ey * ey)
        points, at = robot_points[r], robot_at[r]
        for q in range(robot_pose.shape[1]):
            live = not was_done[r, q]
            px, py = robot_pose[r, q, 0], robot_pose[r, q, 1]
            if live:
                if points > 1:
                    deviation[r, q] += np.sqrt(
                        _path_distance2(px, py, robot_track, robot_box, at, points, chunk, box_gap)
                    )
                moves[r, q] += 1
            bx, by = robot_before[r, q, 0], robot_before[r, q, 1]
            rvx, rvy = (px - bx) / dt, (py - by) / dt  # the robot's velocity through the step
            for s in range(people[r]):
                if in_step:  # the CrowdNav task's judgement: the closest approach during the step
                    close, dx, dy, vx, vy, ox, oy = False, 0.0, 0.0, 0.0, 0.0, rvx, rvy
                    if mask_before[r, s]:  # only those present before the step (a row has many free slots)
                        sx, sy = pos_before[r, s, 0] - bx, pos_before[r, s, 1] - by
                        vx, vy = vel_before[r, s, 0], vel_before[r, s, 1]
                        mx, my = (vx - rvx) * dt, (vy - rvy) * dt
                        a, c, f = mx * mx + my * my, sx * sx + sy * sy - collision2, 0.0
                        # A person farther than the collision distance plus the relative move cannot touch:
                        # s^2 > 2 (collision^2 + m^2) >= (collision + |m|)^2, said without a square root.
                        close = c <= collision2 + 2.0 * a and closest_gap(sx, sy, mx, my, collision) < 0
                        # The contact began where the relative move first came within touching.
                        if close and a > 0 and c > 0:
                            half = sx * mx + sy * my
                            f = min(max((-half - np.sqrt(max(half * half - a * c, 0.0))) / a, 0.0), 1.0)
                        dx, dy = sx + f * mx, sy + f * my
                else:  # the world's contacts at the step's end
                    dx, dy = pos_after[r, s, 0] - px, pos_after[r, s, 1] - py
                    close = dx * dx + dy * dy < collision2 and human_mask[r, s]
                    vx, vy = human_vel[r, s, 0], human_vel[r, s, 1]
                    ox, oy = robot_vel[r, q, 0], robot_vel[r, q, 1]
                if close and not contact[r, q, s] and live:
                    norm = max(np.sqrt(dx * dx + dy * dy), 1e-9)
                    ux, uy = dx / norm, dy / norm
                    person_in = -(vx * ux + vy * uy)
                    robot_in = ox * ux + oy * uy
                    if person_in > robot_in:
                        walked_into[r, q] += 1
                contact[r, q, s] = close


@kernel
def _path_distance2(px, py, path, box, at, points, chunk, box_gap):  # type: ignore[no-untyped-def]
    """The least squared distance from (px, py) to the polyline of `points` points of `path` from `at`
    (one square root of it is the least of the segments' distances exactly: sqrt is monotone).

    The segments' boxes (`box` at every `chunk`-th point) are visited nearest first, and the search
    stops at a box farther than the least distance found (with a slack far above rounding): no
    segment in it can be nearer, so the least is the same as over every segment, in fewer divisions."""
    boxes = (points - 2) // chunk + 1
    for c in range(boxes):
        k = at + c * chunk
        gx = max(box[k, 0] - px, px - box[k, 2], 0.0)
        gy = max(box[k, 1] - py, py - box[k, 3], 0.0)
        box_gap[c] = gx * gx + gy * gy
    nearest2 = np.inf
    while True:
        best, low = -1, np.inf
        for c in range(boxes):
            if box_gap[c] < low:
                best, low = c, box_gap[c]
        if best < 0 or low > nearest2 * (1.0 + 1e-9):
            return nearest2
        box_gap[best] = np.inf
        first = at + best * chunk
        for k in range(first, min(first + chunk, at + points - 1)):
            ax, ay = path[k, 0], path[k, 1]
            abx, aby = path[k + 1, 0] - ax, path[k + 1, 1] - ay
            u = ((px - ax) * abx + (py - ay) * aby) / max(abx * abx + aby * aby, 1e-12)
            u = min(max(u, 0.0), 1.0)
            cx, cy = ax + u * abx - px, ay + u * aby - py
            nearest2 = min(nearest2, cx * cx + cy * cy)


@kernel
def row_measures(
    rows, robots, reacted_at, exit_at, rest, elapsed, occupant, slot_at, people, occupants_at, speed, recorded_exit,
    walked, recorded_left, folded, frame_dt, robot_points, deviation, moves, walked_into, measures,
):  # fmt: skip
    """ReplayRunner.summaries' numbers of `rows` for robot robots[j] of row j, into measures (n, 6): the
    reacting people's count, time lost and extra distance; the replaced person's time (NaN without a path);
    the robot's mean distance to that person's path (NaN without moves or a path of 2 points); and the people
    who walked into the robot.

    The reacting people are those who left their slot (`folded`) plus those still in one, in slot order:
    each one's time to its exit (or, not gone yet, the episode's time) plus the straight way left to its
    route's end at its speed, against its recorded exit, and its distance walked plus that way left against
    the recorded distance left. Every one is counted to its route's end: one who left did so within the
    waypoint radius of it, and its way left is from where it left."""
    for j in range(rows.shape[0]):
        r, q = rows[j], robots[j]
        count, lost, extra = 0, 0.0, 0.0
        for s in range(people[r]):  # a row without a recording has none
            if reacted_at[r, s] != reacted_at[r, s]:  # NaN: it did not react
                continue
            done = exit_at[r, s] == exit_at[r, s]
            own = max(speed[occupants_at[slot_at[r] + s] + max(occupant[r, s], 0)], 1e-9)
            at = (exit_at[r, s] if done else elapsed[r]) + rest[r, s] / own
            lost += at - recorded_exit[r, s]
            extra += walked[r, s] + rest[r, s] - recorded_left[r, s]
            count += 1
        measures[j, 0] = folded[r, 0] + count
        measures[j, 1] = folded[r, 1] + lost
        measures[j, 2] = folded[r, 2] + extra
        points = robot_points[r]
        measures[j, 3] = (points - 1) * frame_dt[r] if points > 0 else np.nan
        measures[j, 4] = deviation[r, q] / moves[r, q] if moves[r, q] > 0 and points > 1 else np.nan
        measures[j, 5] = walked_into[r, q]
