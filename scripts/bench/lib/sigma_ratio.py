#!/usr/bin/env python3
"""Median |distance to the true surface| / s_normal over the points of a
`bayon evaluate --cloud_errors_path` PLY that lie within 5 GSD (the rest
are blunders, counted apart): how the stated standard deviations compare
with the true errors (1: as stated; above 1: errors larger than stated).
   sigma_ratio.py ERRORS.ply GSD_M"""
import struct
import sys

TYPES = {"double": "d", "float": "f", "uchar": "B", "int": "i", "uint": "I",
         "char": "b", "short": "h", "ushort": "H"}


def read_ply(path):
    with open(path, "rb") as f:
        names, fmt, count = [], "<", 0
        while True:
            line = f.readline().decode("ascii").strip()
            if line.startswith("element vertex"):
                count = int(line.split()[2])
            elif line.startswith("element") and count:
                break
            elif line.startswith("property"):
                _, kind, name = line.split()
                names.append(name)
                fmt += TYPES[kind]
            if line == "end_header":
                break
        size = struct.calcsize(fmt)
        data = f.read(size * count)
    for i in range(count):
        yield dict(zip(names, struct.unpack_from(fmt, data, i * size)))


def main():
    path, gsd = sys.argv[1], float(sys.argv[2])
    ratios, blunders = [], 0
    for p in read_ply(path):
        if abs(p["distance_m"]) > 5 * gsd:
            blunders += 1
        elif p["s_normal"] > 0:
            ratios.append(abs(p["distance_m"]) / p["s_normal"])
    ratios.sort()
    median = ratios[len(ratios) // 2] if ratios else float("nan")
    # |e| / sigma of a normal error has a median of 0.674.
    print("%.2f %d" % (median / 0.6745, blunders))


main()
