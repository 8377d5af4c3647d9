#!/usr/bin/env python3
"""Reads an NC program with LinuxCNC's standalone interpreter `rs274` and
sums its canonical moves, as an independent check of thinplan's post.

    python3 tools/peers/linuxcnc/rs274_check.py PROGRAM.ngc TOOLS.tbl [--skip N]

Prints one JSON object: ok (no interpreter error), error (its message),
feed_length_mm (STRAIGHT_FEED + ARC_FEED, helices included), rapid_length_mm
(STRAIGHT_TRAVERSE), counts, arc turns. `--skip N` leaves the first N motion
moves out of the lengths: they start where the interpreter happens to begin
(0, 0, 0), not at a place the program set (thinplan reports that count as
`unmeasured_moves`). Exit status: 0 when the interpreter read the whole
program, 1 on an interpreter error, 2 when rs274 is not installed (run
setup.sh).
"""
import argparse
import fcntl
import json
import math
import os
import re
import subprocess
import sys

CALL = re.compile(r"^\s*\d+\s+N\S*\s+([A-Z_0-9]+)\((.*)\)\s*$")
NUM = re.compile(r"[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?")


def find_root():
    return os.environ.get("THINPLAN_LINUXCNC") or os.path.join(
        os.path.expanduser("~"), ".cache", "thinplan-linuxcnc"
    )


def run_rs274(root, program, table):
    exe = os.path.join(root, "usr", "bin", "rs274")
    if not os.access(exe, os.X_OK):
        return None
    env = dict(os.environ)
    libs = [os.path.join(root, "usr", "lib"), os.path.join(root, "usr", "lib", "x86_64-linux-gnu")]
    env["LD_LIBRARY_PATH"] = ":".join(libs + [env.get("LD_LIBRARY_PATH", "")])
    # Two rs274 processes at once share the tool-data memory map and one of
    # them dies of SIGBUS (seen with parallel tests): one at a time.
    with open(os.path.join(root, ".rs274.lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        return subprocess.run(
            [exe, "-t", table, "-g", program],
            stdin=subprocess.DEVNULL,
            capture_output=True,
            text=True,
            env=env,
            timeout=600,
        )


def arc_length(start, end, centre, rotation, axis_start, axis_end):
    """Length of a canonical ARC_FEED in its plane coordinates (first, second)."""
    sx, sy = start[0] - centre[0], start[1] - centre[1]
    ex, ey = end[0] - centre[0], end[1] - centre[1]
    r = 0.5 * (math.hypot(sx, sy) + math.hypot(ex, ey))
    a0, a1 = math.atan2(sy, sx), math.atan2(ey, ex)
    turns = abs(rotation)
    if rotation > 0:  # counter-clockwise
        sweep = (a1 - a0) % (2 * math.pi)
    else:
        sweep = (a0 - a1) % (2 * math.pi)
    if sweep < 1e-12:
        sweep = 2 * math.pi
    sweep += 2 * math.pi * (turns - 1)
    return math.hypot(r * sweep, axis_end - axis_start), sweep


def summarise(stdout, skip):
    pos = [0.0, 0.0, 0.0]  # the interpreter starts at the origin
    plane = "CANON_PLANE_XY"
    out = {
        "feed_length_mm": 0.0,
        "rapid_length_mm": 0.0,
        "traverse_count": 0,
        "straight_feed_count": 0,
        "arc_count": 0,
        "arc_turns": 0.0,
        "tool_changes": 0,
        "skipped_moves": 0,
        "units": "mm",
    }
    moves = 0
    for line in stdout.splitlines():
        m = CALL.match(line)
        if not m:
            continue
        name, args = m.group(1), m.group(2)
        if name == "SELECT_PLANE":
            plane = args.strip()
            continue
        if name == "USE_LENGTH_UNITS":
            if "MM" not in args:
                out["units"] = args.strip()
            continue
        if name == "CHANGE_TOOL":
            out["tool_changes"] += 1
            continue
        if name not in ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED", "ARC_FEED"):
            continue
        v = [float(x) for x in NUM.findall(args)]
        counted = moves >= skip
        moves += 1
        if not counted:
            out["skipped_moves"] += 1
        if name in ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED"):
            new = v[0:3]
            length = math.dist(pos, new)
            if name == "STRAIGHT_TRAVERSE":
                out["traverse_count"] += 1
                if counted:
                    out["rapid_length_mm"] += length
            else:
                out["straight_feed_count"] += 1
                if counted:
                    out["feed_length_mm"] += length
            pos = new
            continue
        # ARC_FEED(first_end, second_end, first_axis, second_axis, rotation,
        #          axis_end_point, a, b, c, …) in the selected plane.
        first_end, second_end, first_c, second_c, rotation, axis_end = v[0:6]
        rotation = int(rotation)
        # (first, second, axis) as indices into x y z, per canon's planes.
        idx = {
            "CANON_PLANE_XY": (0, 1, 2),
            "CANON_PLANE_YZ": (1, 2, 0),
            "CANON_PLANE_XZ": (2, 0, 1),
        }[plane]
        start = (pos[idx[0]], pos[idx[1]])
        length, sweep = arc_length(
            start, (first_end, second_end), (first_c, second_c), rotation, pos[idx[2]], axis_end
        )
        out["arc_count"] += 1
        out["arc_turns"] += sweep / (2 * math.pi)
        if counted:
            out["feed_length_mm"] += length
        new = [0.0, 0.0, 0.0]
        new[idx[0]], new[idx[1]], new[idx[2]] = first_end, second_end, axis_end
        pos = new
    out["final_position"] = pos
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("program")
    ap.add_argument("tool_table")
    ap.add_argument("--skip", type=int, default=0, help="leading motion moves left out of the lengths")
    ap.add_argument("--root", default=None, help="unpacked linuxcnc-uspace (default ~/.cache/thinplan-linuxcnc)")
    a = ap.parse_args()
    root = a.root or find_root()
    proc = run_rs274(root, a.program, a.tool_table)
    if proc is None:
        print(json.dumps({"ok": False, "error": f"rs274 not found under {root}: run tools/peers/linuxcnc/setup.sh"}))
        return 2
    # rs274 writes "executing" and any interpreter error (message, then the
    # offending block) to stderr, and exits 1 on an error.
    err_lines = [l for l in proc.stderr.splitlines() if l.strip() and l.strip() != "executing"]
    out = summarise(proc.stdout, a.skip)
    out["ok"] = proc.returncode == 0 and not err_lines and out["units"] == "mm"
    if err_lines:
        out["error"] = "\n".join(err_lines)
    elif proc.returncode < 0:
        out["error"] = f"rs274 killed by signal {-proc.returncode}"
    elif proc.returncode != 0:
        out["error"] = f"rs274 exited with {proc.returncode} and no message"
    else:
        out["error"] = "" if out["units"] == "mm" else "not metric"
    out["returncode"] = proc.returncode
    out["program"] = a.program
    print(json.dumps(out, indent=1, sort_keys=True))
    return 0 if out["ok"] else 1


if __name__ == "__main__":
    sys.exit(main())
