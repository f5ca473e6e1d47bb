#!/usr/bin/env python3
"""Issue 13 (sizes): every scene x seed x model with the gaussian sensor at realistic noise.

Usage: tools/measure_sizes.py BINARY OUTDIR [--scenes a,b] [--seeds 1-5] [--models paper,rooms]
Prints one row per scene and model: mean recall, precision, f1 over seeds, and for each run the
sizes judged within 5 cm (the rooms model's report; the paper's maps judged here the same way
from map.json against the scene), split/merged objects, phantoms near walls, and wall time.
"""
import json, math, os, subprocess, sys, time

def canon(t):
    w, d, th = t.get('width', 0.8), t.get('depth', 0.5), t.get('theta', 0.0)
    if d > w:
        w, d, th = d, w, th + math.pi / 2
    return w, d, t.get('leg', 0.05), th

def wrap(a, p):
    a = math.fmod(a + 0.5 * p, p)
    if a < 0: a += p
    return a - 0.5 * p

def sized_eval(m, scene, tol=0.05):
    """Sized matching as host/src/mapping/evaluation.cc does with MatchTolerance::size = tol."""
    truth = scene['tables']
    pairs = []
    for i, t in enumerate(m['tables']):
        mw, md, ml, mth = canon(t)
        for j, s in enumerate(truth):
            w, d, l, th = canon(s)
            dist = math.hypot(t['x'] - s['x'], t['y'] - s['y'])
            sq = abs(mw - md) <= tol and abs(w - d) <= tol
            ang = abs(wrap(mth - th, math.pi / 2 if sq else math.pi))
            if dist <= 0.15 and ang <= 15 * math.pi / 180 and abs(mw - w) <= tol and \
               abs(md - d) <= tol and abs(ml - l) <= tol:
                pairs.append((dist, i, j))
    pairs.sort()
    fu, tu, n = set(), set(), 0
    for _, i, j in pairs:
        if i in fu or j in tu: continue
        fu.add(i); tu.add(j); n += 1
    nf, nt = len(m['tables']), len(truth)
    p = 1.0 if nf == 0 else n / nf
    r = 1.0 if nt == 0 else n / nt
    return r, p

def main():
    b, out = sys.argv[1], sys.argv[2]
    args = dict(zip(sys.argv[3::2], sys.argv[4::2]))
    scenes = args.get('--scenes', 'default,' + ','.join(sorted(
        f[:-5] for f in os.listdir('test/scenes') if f.endswith('.json') and
        not f.startswith(('bad_', 'hil_', 'physics_', 'large_floor')))))
    lo, hi = map(int, args.get('--seeds', '1-5').split('-'))
    models = args.get('--models', 'paper,rooms').split(',')
    print('scene,model,recall,precision,f1,sized_recall,sized_precision,split,merged,'
          'phantoms_near_walls,seconds')
    for sc in scenes.split(','):
        scene_file = None if sc == 'default' else f'test/scenes/{sc}.json'
        for model in models:
            acc = []
            for seed in range(lo, hi + 1):
                d = f'{out}/{sc}_{model}_{seed}'
                cmd = [b, '--sim', '--sensor-model', 'gaussian', '--noise', 'realistic',
                       '--seed', str(seed), '--model', model, '--out', d]
                if scene_file: cmd += ['--scene', scene_file]
                t0 = time.time()
                subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                dt = time.time() - t0
                rep = json.load(open(f'{d}/report.json'))['accuracy']
                m = json.load(open(f'{d}/map.json'))
                scene = json.load(open(scene_file)) if scene_file else None
                if scene is None:
                    scene = {'tables': []}  # default arena: sized recall from the report only
                    sr, sp = rep['recall'], rep['precision']
                else:
                    sr, sp = sized_eval(m, scene)
                acc.append((rep['recall'], rep['precision'], rep['f1'], sr, sp,
                            rep.get('split_objects', 0), rep.get('merged_objects', 0),
                            rep['phantoms_near_walls'], dt))
            n = len(acc)
            mean = [sum(a[k] for a in acc) / n for k in range(9)]
            print(f'{sc},{model},' + ','.join(f'{v:.3f}' for v in mean), flush=True)

main()
