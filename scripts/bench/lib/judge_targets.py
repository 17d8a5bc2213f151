#!/usr/bin/env python3
"""Coded targets measured by `bayon targets` against a synthetic tower's
truth (scripts/bench/targets.sh): found among the visible ones, wrong codes,
centre RMS, stated sigmas.
   judge_targets.py WORKSPACE MEASUREMENTS SECONDS PEAK_MB"""
import math
import sys


def measurements(path, prefix="CT"):
    """(image, name) -> (x, y, sigma) from a control/observations.txt file."""
    out = {}
    for line in open(path):
        f = line.split()
        if not f or f[0].startswith("#") or not f[0].startswith(prefix):
            continue
        out[(f[1], f[0])] = (float(f[2]), float(f[3]),
                             float(f[4]) if len(f) > 4 else 0.0)
    return out


def camera(path):
    """The truth's FULL_OPENCV camera: fx fy cx cy k1 k2 p1 p2 k3 k4 k5 k6."""
    for line in open(path):
        f = line.split()
        if f and not f[0].startswith("#"):
            assert f[1] == "FULL_OPENCV", f[1]
            return list(map(float, f[4:16]))


def poses(path):
    """image name -> (qw, qx, qy, qz, tx, ty, tz) from COLMAP's images.txt."""
    lines = [l for l in open(path) if not l.startswith("#")]
    return {lines[i].split()[9]: list(map(float, lines[i].split()[1:8]))
            for i in range(0, len(lines), 2)}


def project(cam, pose, point):
    fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6 = cam
    w, x, y, z = pose[:4]
    rot = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
           [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
           [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    p = [sum(rot[r][c] * point[c] for c in range(3)) + pose[4 + r]
         for r in range(3)]
    u, v = p[0] / p[2], p[1] / p[2]
    r2 = u * u + v * v
    radial = (1 + k1 * r2 + k2 * r2 ** 2 + k3 * r2 ** 3) / \
        (1 + k4 * r2 + k5 * r2 ** 2 + k6 * r2 ** 3)
    ud = u * radial + 2 * p1 * u * v + p2 * (r2 + 2 * u * u)
    vd = v * radial + p1 * (r2 + 2 * v * v) + 2 * p2 * u * v
    return fx * ud + cx, fy * vd + cy


def main():
    ws, found_path, seconds, peak = sys.argv[1:5]
    truth = measurements(ws + "/gt/control/observations.txt")
    found = measurements(found_path)
    points = {}
    for line in open(ws + "/gt/control/points.txt"):
        f = line.split()
        if f and not f[0].startswith("#"):
            points[f[0]] = tuple(map(float, f[1:4]))
    cam = camera(ws + "/gt/sparse/cameras.txt")
    pose = poses(ws + "/gt/sparse/images.txt")
    wrong = 0
    for (image, name), (x, y, _) in found.items():
        u, v = project(cam, pose[image], points[name])
        wrong += math.hypot(u - x, v - y) > 3
    hit = [k for k in truth if k in found]
    errors = [math.hypot(found[k][0] - truth[k][0], found[k][1] - truth[k][1])
              for k in hit]
    sigmas = sorted(found[k][2] for k in hit)
    rms = math.sqrt(sum(e * e for e in errors) / len(errors))
    # The stated SIGMA is the covariance's larger axis; beside it the true
    # error per axis (the radial RMS over the square root of 2).
    stated = math.sqrt(sum(s * s for s in sigmas) / len(sigmas))
    print("| visible | found | wrong codes | measurements | centre RMS | max "
          "| per axis: true / stated (RMS) | time | peak |")
    print("|---|---|---|---|---|---|---|---|---|")
    print("| %d | %d (%.1f %%) | %d | %d | %.3f px | %.3f px "
          "| %.3f / %.3f px | %s s | %s MB |"
          % (len(truth), len(hit), 100.0 * len(hit) / len(truth), wrong,
             len(found), rms, max(errors), rms / math.sqrt(2), stated,
             seconds, peak))
    missed = sorted(k for k in truth if k not in found)
    if missed:
        print("missed: " + ", ".join("%s in %s" % (n, i) for i, n in missed))


if __name__ == "__main__":
    main()
