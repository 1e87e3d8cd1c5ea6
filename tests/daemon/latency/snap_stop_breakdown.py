#!/usr/bin/env python3
"""snap_stop_breakdown.py: where a rig trial's snap-to-stop time went (issue 34 F).

Reads one trial's store (its "snap-to-stop breakdown" event, trial_latency.h) and ribbon-rigsim's
truth log (--truth: the twin's Delta Z at each image's send time) and axes log (--axes-log: both
axes every 5 ms), all on CLOCK_MONOTONIC, and prints one JSON line with, in ms:
  true_snap_to_det_frame  the twin's snap (first image whose |dDeltaZ/dt| exceeds the scene's
                          snap speed) -> the detection frame's own time (the detector's frames)
  frame_to_arrival        detection frame's stamp -> its arrival on the host (transport)
  arrival_to_picked       arrival -> the trial loop took it from the ring (the loop behind)
  picked_to_tracked       -> the tracker was done with it
  tracker_cpu             the loop thread's CPU in the tracker on that frame (the rest: waiting)
  tracked_to_decided      -> the loop had stored its sample and judged it (store, detector)
  decided_to_stop_ret     the stop asked -> the stop command returned (rails' lock + write)
  stop_to_decel           stop returned -> the shear axis slows (below 95% of its speed; axes log)
  stop_to_rest            stop returned -> the shear axis at rest (axes log, 5 ms resolution)
  rest_to_read            at rest -> the first fresh reading standing (the poll)
  det_to_read             detection frame -> read standing (the stored stop_stand_latency_s)
  decel_theory            v / a of the rig file (the deceleration alone)
Usage: snap_stop_breakdown.py DB TRUTH.csv AXES.csv [--trial 1] [--snap-speed 1.0] [--label X]"""
import csv
import json
import re
import sqlite3
import sys


def main(argv):
    args = [a for a in argv[1:]]
    opt = {"--trial": "1", "--snap-speed": "1.0", "--label": "", "--v": "10", "--a": "200"}
    pos = []
    i = 0
    while i < len(args):
        if args[i] in opt and i + 1 < len(args):
            opt[args[i]] = args[i + 1]
            i += 2
        else:
            pos.append(args[i])
            i += 1
    if len(pos) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    db, truth, axes = pos
    con = sqlite3.connect("file:%s?mode=ro" % db, uri=True)
    row = con.execute("select message from events where trial_id = ? and message like 'snap-to-stop breakdown:%'",
                      (int(opt["--trial"]),)).fetchone()
    if not row:
        print(json.dumps({"label": opt["--label"], "error": "no snap-to-stop breakdown event in the trial"}))
        return 1
    msg = row[0]
    st = con.execute("select status, stop_cmd_latency_s, stop_stand_latency_s from trials where id = ?",
                     (int(opt["--trial"]),)).fetchone()

    def ms(label):
        m = re.search(re.escape(label) + r" (-?[0-9.]+) ms", msg)  # "n/a" -> None
        return float(m.group(1)) if m else None

    t0 = float(re.search(r"t0_mono ([0-9.]+)", msg).group(1))
    head = re.search(r"detection frame (-?\d+) \(at (-?[0-9.]+|nan) s\) (-?[0-9.]+) ms", msg)
    t_det = float(head.group(2)) + t0
    out = {"label": opt["--label"], "status": st[0] if st else None}
    out["onset_to_det_frame"] = float(head.group(3))
    out["frame_to_arrival"] = ms("-> arrival")
    out["arrival_to_picked"] = ms("-> picked up")
    out["picked_to_tracked"] = ms("-> tracked")
    out["tracked_to_decided"] = ms("-> decided")
    cpu = re.search(r"\(CPU ([0-9.]+) ms\)", msg)
    out["tracker_cpu"] = float(cpu.group(1)) if cpu else None
    out["decided_to_stop_ret"] = ms("-> stop returned")
    out["stop_to_read"] = ms("read standing")
    out["det_to_read"] = ms("total")
    parts = [out[k] for k in ("frame_to_arrival", "arrival_to_picked", "picked_to_tracked", "tracked_to_decided",
                              "decided_to_stop_ret")]
    t_stop = t_det + sum(p for p in parts if p is not None) / 1e3
    t_read = None if out["stop_to_read"] is None else t_stop + out["stop_to_read"] / 1e3

    # The twin's snap in the truth log: the first image whose Delta Z moves faster than snap speed.
    speed = float(opt["--snap-speed"])
    prev = None
    t_true = None
    with open(truth) as f:
        for r in csv.DictReader(f):
            t, dz = float(r["mono_s"]), float(r["dz"])
            if prev and t > prev[0] and t_det - 2.0 < t < t_det + 1.0 and abs(dz - prev[1]) / (t - prev[0]) > speed:
                t_true = t
                break
            prev = (t, dz)
    out["true_snap_to_det_frame"] = None if t_true is None else round(1e3 * (t_det - t_true), 1)

    # The shear axis after the stop: when it slows and when it stands (axes log, 5 ms lines).
    rows = []
    with open(axes) as f:
        for r in csv.DictReader(f):
            t = float(r["mono_s"])
            if t_stop - 0.3 <= t <= t_stop + 1.0:
                rows.append((t, float(r["shear_mm"])))
    # Slowing: the first 5 ms step below 95% of the shear speed; at rest: the first step with no
    # more forward motion (a return that starts before the rest reverses instead of standing).
    v_cmd = float(opt["--v"])
    t_decel = t_rest = None
    direction = 0.0
    for k in range(1, len(rows)):
        t, x = rows[k]
        dt = t - rows[k - 1][0]
        if dt <= 0:
            continue
        v = (x - rows[k - 1][1]) / dt
        if t < t_stop - 0.05:
            if abs(v) > 0.5 * v_cmd:
                direction = 1.0 if v > 0 else -1.0
            continue
        if t_decel is None and abs(v) < 0.95 * v_cmd:
            t_decel = rows[k - 1][0]
        if t_decel is not None and t_rest is None and direction * v <= 1e-3:
            t_rest = rows[k - 1][0]
            break
    out["stop_to_decel"] = None if t_decel is None else round(1e3 * (t_decel - t_stop), 1)
    out["stop_to_rest"] = None if t_rest is None else round(1e3 * (t_rest - t_stop), 1)
    out["rest_to_read"] = None if t_rest is None or t_read is None else round(1e3 * (t_read - t_rest), 1)
    out["decel_theory"] = round(1e3 * float(opt["--v"]) / float(opt["--a"]), 1)
    out["stop_cmd_latency_ms"] = None if not st or st[1] is None else round(1e3 * st[1], 1)
    out["stop_stand_latency_ms"] = None if not st or st[2] is None else round(1e3 * st[2], 1)
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
