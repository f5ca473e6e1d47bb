#!/usr/bin/env python3
"""Walls (issue 13): every test/scenes/ scene x seeds x object model through
`crunchhost --sim --sensor-model gaussian --noise realistic`, one markdown row per scene and
model: tables (recall, precision, F1, wall phantoms summed over seeds) and walls
(report.json accuracy.walls: boundary coverage, interior found, false length), and the mean
wall-clock time per run.

usage: tools/wall-table.py [--bin build/default/host/app/crunchhost] [--seeds 1-5]
                           [--models paper,rooms] [--out /tmp/wall-table]
"""
import argparse, json, os, subprocess, sys, time

ap = argparse.ArgumentParser()
ap.add_argument("--bin", default="build/default/host/app/crunchhost")
ap.add_argument("--seeds", default="1-5")
ap.add_argument("--models", default="paper,rooms")
ap.add_argument("--out", default="/tmp/wall-table")
ap.add_argument("--scenes", default="")
a = ap.parse_args()
lo, hi = (int(x) for x in a.seeds.split("-"))
scenes = a.scenes.split(",") if a.scenes else sorted(
    f[:-5] for f in os.listdir("test/scenes") if f.endswith(".json") and not f.startswith("bad_"))
scenes = ["(default)"] + [s for s in scenes if s != "(default)"]
print("| scene | model | recall | precision | F1 | wall phantoms | boundary cov. | interior found | false walls m | s/run |")
print("|---|---|---|---|---|---|---|---|---|---|")
for sc in scenes:
    for m in a.models.split(","):
        acc, walls, secs = [], [], []
        for seed in range(lo, hi + 1):
            out = os.path.join(a.out, f"{sc}_{m}_{seed}")
            cmd = [a.bin, "--sim", "--sensor-model", "gaussian", "--noise", "realistic",
                   "--seed", str(seed), "--model", m, "--out", out]
            if sc != "(default)":
                cmd += ["--scene", f"test/scenes/{sc}.json"]
            t0 = time.time()
            r = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            secs.append(time.time() - t0)
            if r.returncode != 0:
                print(f"{sc} {m} {seed}: exit {r.returncode}: {r.stderr[-300:]}", file=sys.stderr)
                continue
            rep = json.load(open(os.path.join(out, "report.json")))
            acc.append(rep["accuracy"])
            if "walls" in rep["accuracy"]:
                walls.append(rep["accuracy"]["walls"])
        if not acc:
            continue
        mean = lambda k, xs: sum(x[k] for x in xs) / len(xs)
        row = [sc, m, f"{mean('recall', acc):.2f}", f"{mean('precision', acc):.2f}",
               f"{mean('f1', acc):.2f}", str(sum(x["phantoms_near_walls"] for x in acc))]
        if walls:
            row += [f"{mean('boundary_coverage', walls):.2f} (min {min(w['boundary_coverage'] for w in walls):.2f})",
                    f"{mean('interior_found', walls):.2f}" if any(w["interior_length_m"] > 0 for w in walls) else "-",
                    f"{mean('false_length_m', walls):.2f}"]
        else:
            row += ["-", "-", "-"]
        row.append(f"{sum(secs) / len(secs):.2f}")
        print("| " + " | ".join(row) + " |", flush=True)
