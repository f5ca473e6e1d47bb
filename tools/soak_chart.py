#!/usr/bin/env python3
"""Charts a soak run (tools/soak.sh): crunchhost --robot --json's "status" lines over time.

usage: soak_chart.py PROGRESS_JSONL REPORT_JSON OUT_DIR
Writes OUT_DIR/status.csv (t_s, rss_mib, ring_high_water, ring_dropped, lost_frames,
watchdog_stops, map_write_last_s, map_write_max_s) and OUT_DIR/soak.png (four panels), and
prints a summary; exits 1 when the run's checks fail: resident memory grew more than 10 % from
the second tenth of the run to the last (median over each; the first is warm-up), frames were lost, the ring dropped
chunks, or the watchdog stopped the Create.
"""
import csv
import json
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    progress, report_path, out = sys.argv[1:4]
    rows = []
    with open(progress) as f:
        for line in f:
            if not line.startswith("{"):
                continue
            e = json.loads(line)
            if e.get("event") == "status":
                rows.append(e)
    if len(rows) < 3:
        print(f"soak_chart: only {len(rows)} status lines in {progress}", file=sys.stderr)
        return 1
    cols = ["t", "rss_kib", "ring_high_water", "ring_dropped", "lost_frames", "watchdog_stops",
            "map_write_last_s", "map_write_max_s"]
    with open(f"{out}/status.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t_s", "rss_mib"] + cols[2:])
        for r in rows:
            w.writerow([r["t"], r["rss_kib"] / 1024] + [r[c] for c in cols[2:]])

    t = [r["t"] / 60 for r in rows]
    fig, ax = plt.subplots(4, 1, figsize=(9, 10), sharex=True)
    ax[0].plot(t, [r["rss_kib"] / 1024 for r in rows])
    ax[0].set_ylabel("resident memory, MiB")
    ax[1].plot(t, [r["ring_high_water"] for r in rows], label="ring high water (slots)")
    ax[1].plot(t, [r["ring_dropped"] for r in rows], label="ring dropped (chunks)")
    ax[1].legend(loc="upper left")
    ax[2].plot(t, [r["lost_frames"] for r in rows], label="frames lost before the host")
    ax[2].plot(t, [r["watchdog_stops"] for r in rows], label="Create watchdog stops")
    ax[2].legend(loc="upper left")
    ax[3].plot(t, [1000 * r["map_write_last_s"] for r in rows], label="last write")
    ax[3].plot(t, [1000 * r["map_write_max_s"] for r in rows], label="largest so far")
    ax[3].set_ylabel("map write, ms")
    ax[3].legend(loc="upper left")
    ax[3].set_xlabel("simulated time, minutes")
    fig.suptitle(f"crunchhost --robot soak in crunch-virtual-robot: {rows[-1]['t'] / 60:.0f} min")
    fig.tight_layout()
    fig.savefig(f"{out}/soak.png", dpi=90)

    # The second tenth, not the first: the first holds the warm-up (calibration, the first
    # whisks, the allocator's first arenas).
    tenth = max(1, len(rows) // 10)
    rss_first = statistics.median(r["rss_kib"] for r in rows[tenth:2 * tenth]) / 1024
    rss_last = statistics.median(r["rss_kib"] for r in rows[-tenth:]) / 1024
    last = rows[-1]
    failures = []
    if rss_last > 1.10 * rss_first:
        failures.append(f"memory grew {rss_first:.1f} -> {rss_last:.1f} MiB")
    for key in ("lost_frames", "ring_dropped", "watchdog_stops"):
        if last[key] != 0:
            failures.append(f"{key} {last[key]}")
    summary = {
        "status_lines": len(rows), "minutes": round(last["t"] / 60, 1),
        "rss_mib_second_tenth": round(rss_first, 1), "rss_mib_last_tenth": round(rss_last, 1),
        "rss_mib_max": round(max(r["rss_kib"] for r in rows) / 1024, 1),
        "ring_high_water": max(r["ring_high_water"] for r in rows),
        "ring_dropped": last["ring_dropped"], "lost_frames": last["lost_frames"],
        "watchdog_stops": last["watchdog_stops"], "map_writes": last["map_writes"],
        "map_write_failures": last["map_write_failures"],
        "map_write_max_ms": round(1000 * last["map_write_max_s"], 1),
        "map_write_median_ms": round(1000 * statistics.median(
            r["map_write_last_s"] for r in rows), 1),
    }
    try:
        with open(report_path) as f:
            report = json.load(f)
        summary["stop"] = report.get("stop")
        summary["tables"] = report.get("map", {}).get("tables")
        summary["shapelets"] = report.get("map", {}).get("shapelets")
    except (OSError, ValueError) as e:
        failures.append(f"no report: {e}")
    print(json.dumps(summary))
    if failures:
        print("soak: FAILED: " + "; ".join(failures), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
