#!/usr/bin/env python3
"""Constrained requests and homotopy classes (a measurement only): for seeded
cases of scripts/extremal_classes.py's suite, the unconstrained default plan's peak |tau|, then the
same request under max_torque_norm = FRACTION x that peak, planned by default and in each forced
class (--direction, --extra-revolutions); prints how often the default is costlier than a class.
  /usr/bin/python3 scripts/extremal_classes_constrained.py PLAN_MANEUVER SEED COUNT FRACTION
(docs/results/extremal_classes.md, "Constrained requests".)"""
import csv, importlib.util, math, os, subprocess, sys, time

import numpy as np

spec = importlib.util.spec_from_file_location(
    "ec", os.path.join(os.path.dirname(os.path.abspath(__file__)), "extremal_classes.py"))
ec = importlib.util.module_from_spec(spec); spec.loader.exec_module(ec)
P = sys.argv[1]
rng = np.random.default_rng(int(sys.argv[2])); count = int(sys.argv[3]); frac = float(sys.argv[4])
os.makedirs('/tmp/extremal_classes_constrained', exist_ok=True)
costlier = 0; n = 0; worst = 1.0; t0 = time.time()
for i in range(count):
    c = ec.draw_case(rng, i)
    base = ec.scene_text(c)
    scene = '/tmp/extremal_classes_constrained/c.yaml'; summ = '/tmp/extremal_classes_constrained/s.json'
    open(scene, 'w').write(base)
    subprocess.run([P, scene, '--summary', summ, '--csv', '/tmp/extremal_classes_constrained/p.csv'], capture_output=True)
    try:
        rows = list(csv.DictReader(open('/tmp/extremal_classes_constrained/p.csv')))
        peak = max(math.sqrt(float(r['tx'])**2 + float(r['ty'])**2 + float(r['tz'])**2) for r in rows)
    except Exception as e:
        print('case', i, 'no unconstrained plan', e); continue
    limit = frac * peak
    open(scene, 'w').write(base + "constraints: [{max_torque_norm: %.17g}]\n" % limit)
    d = ec.plan(P, scene, summ)
    cl = [ec.plan(P, scene, summ, ['--direction', dd, '--extra-revolutions', str(k)]) for dd, k in ec.CLASSES]
    best = min((x['cost'] for x in cl if x['converged']), default=math.nan)
    if not d['converged'] or math.isnan(best):
        print('case %d: default converged %s, classes converged %d' % (i, d['converged'], sum(x['converged'] for x in cl))); continue
    n += 1
    ratio = d['cost'] / best
    if ratio > 1 + 1e-6: costlier += 1
    worst = max(worst, ratio)
    print('case %d limit %.3g default %.6g best class %.6g ratio %.4f classes %s' % (i, limit, d['cost'], best, ratio, ['%.4g' % x['cost'] if x['converged'] else 'x' for x in cl]), flush=True)
print('SUMMARY seed %s frac %.2f: %d compared, default costlier than another class in %d, worst ratio %.3f, %.0f s' % (sys.argv[2], frac, n, costlier, worst, time.time() - t0))
