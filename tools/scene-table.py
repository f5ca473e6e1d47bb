#!/usr/bin/env python3
"""The scene table of docs/RESULTS.md and docs/BLACKBOARD.md: every scene x object model x seed
mapped by `crunchhost --sim` (gaussian sensor, realistic noise unless --noise), one markdown row
per (scene, model) with the mean over seeds of report.json's accuracy figures, the total of wall
phantoms, the largest model size and the mean wall time.

    python3 tools/scene-table.py [--bin build/default/host/app/crunchhost] [--models paper,rooms,walls:rj,rooms::marginal]
        [--seeds 5] [--scenes default,test/scenes/empty_arena.json,...] [--noise realistic]
        [--jobs 2] [--out build/scene-table] [--columns recall,precision,...]

Without --scenes: the built-in arena and every scene of test/scenes/ that maps with the gaussian
sensor on the pose grid in seconds (not the bad_*, hil_* and physics_* inputs, not large_floor:
add it by name). Each run's report.json and map.json stay in OUT/<scene>/<model>/seed<N>/.
Numbers are read, never computed here, except means, sums and maxima over seeds and
`peak_live_per_object`: (peak live tables + legs) / (real tables + real walls incl. the
arena's four sides), the model-size figure of issue 13 (live walls are not counted yet).
"""
import argparse
import concurrent.futures
import glob
import json
import os
import subprocess
import sys


def flatten(prefix, value, out):
    if isinstance(value, dict):
        for k, v in value.items():
            flatten(f"{prefix}.{k}" if prefix else k, v, out)
    elif isinstance(value, (int, float)) and not isinstance(value, bool):
        out[prefix] = value


def run(binary, scene, model, seed, noise, out_dir):
    os.makedirs(out_dir, exist_ok=True)
    # A model may name its acceptance and its chain fusion after colons: "walls:rj" is
    # --model walls --acceptance rj, "rooms::marginal" --model rooms --chain-fusion marginal.
    name, _, rest = model.partition(":")
    acceptance, _, fusion = rest.partition(":")
    cmd = [binary, "--sim", "--sensor-model", "gaussian", "--noise", noise, "--model", name,
           "--seed", str(seed), "--out", out_dir, "--json"]
    if acceptance:
        cmd += ["--acceptance", acceptance]
    if fusion:
        cmd += ["--chain-fusion", fusion]
    if scene != "default":
        cmd[2:2] = ["--scene", scene]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(out_dir, "report.json")) as f:
        report = json.load(f)
    with open(os.path.join(out_dir, "map.json")) as f:
        m = json.load(f)
    row = {}
    flatten("", report.get("accuracy", {}), row)
    counts = report.get("counts", {})
    row["peak_live_tables"] = counts.get("peak_live_tables", 0)
    row["peak_live_legs"] = counts.get("peak_live_legs", 0)
    row["wall_s"] = report.get("timings_s", {}).get("total", float("nan"))
    row["mapped_walls"] = len(m.get("walls", []))
    real_walls = 4 + scene_walls(scene)
    objects = row.get("true_tables", 0) + real_walls
    row["peak_live_per_object"] = (row["peak_live_tables"] + row["peak_live_legs"]) / objects
    return row


def scene_walls(scene):
    if scene == "default":
        return 0
    with open(scene) as f:
        return len(json.load(f).get("walls", []))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", default="build/default/host/app/crunchhost")
    ap.add_argument("--models", default="paper,rooms")
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--scenes", default="")
    ap.add_argument("--noise", default="realistic")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", default="build/scene-table")
    ap.add_argument("--columns", default="recall,precision,f1,phantoms_near_walls,fused_tables,"
                    "walls.boundary_coverage,walls.interior_found,walls.false_length_m,"
                    "size_error_m.max_width,size_error_m.max_depth,split_objects,"
                    "merged_objects,peak_live_per_object,wall_s")
    a = ap.parse_args()
    if a.scenes:
        scenes = a.scenes.split(",")
    else:
        skip = ("bad_", "hil_", "physics_", "large_floor")
        scenes = ["default"] + sorted(
            p for p in glob.glob("test/scenes/*.json")
            if not os.path.basename(p).startswith(skip))
    models = a.models.split(",")
    jobs = {}
    with concurrent.futures.ThreadPoolExecutor(max_workers=a.jobs) as pool:
        for scene in scenes:
            name = os.path.splitext(os.path.basename(scene))[0]
            for model in models:
                for seed in range(1, a.seeds + 1):
                    out_dir = os.path.join(a.out, name, model, f"seed{seed}")
                    jobs[(scene, model, seed)] = pool.submit(run, a.bin, scene, model, seed,
                                                             a.noise, out_dir)
    columns = a.columns.split(",")
    print(f"{a.seeds} seeds, noise {a.noise}; means over seeds (phantoms: total; "
          f"peak_live_per_object: max)\n")
    print("| scene | model | " + " | ".join(columns) + " |")
    print("|---|---|" + "---|" * len(columns))
    for scene in scenes:
        name = os.path.splitext(os.path.basename(scene))[0]
        for model in models:
            rows = [jobs[(scene, model, s)].result() for s in range(1, a.seeds + 1)]
            cells = []
            for c in columns:
                vals = [r[c] for r in rows if c in r]
                if not vals:
                    cells.append("—")
                elif c.startswith("phantoms"):
                    cells.append(str(int(sum(vals))))
                elif c == "peak_live_per_object":
                    cells.append(f"{max(vals):.1f}")
                elif c in ("fused_tables", "mapped_walls", "split_objects", "merged_objects"):
                    cells.append(f"{sum(vals) / len(vals):.1f}")
                elif c == "wall_s":
                    cells.append(f"{sum(vals) / len(vals):.2f} s")
                elif c.endswith("_m") or c.startswith("size_error_m."):
                    cells.append(f"{1e3 * sum(vals) / len(vals):.1f} mm")
                else:
                    cells.append(f"{sum(vals) / len(vals):.2f}")
            print(f"| {name} | {model} | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
