#!/usr/bin/env python3
"""Error against cell time for grid and optimal plans (scripts/plan-seeds.sh writes the rows).

Usage: cell_time_figure.py ROWS.tsv OUT.svg
ROWS.tsv: name, kind (grid|optimal), cell time (min), work-volume RMS error (mm), tab-separated.
Log-log axes with round ticks (1, 2, 5 steps) and units on both axes.
"""
import math
import sys


def round_ticks(lo, hi):
    """1-2-5 ticks covering [lo, hi] on a log axis."""
    ticks = []
    e = math.floor(math.log10(lo))
    while 10**e <= hi * 10:
        for m in (1, 2, 5):
            v = m * 10**e
            if lo / 1.0001 <= v <= hi * 1.0001:
                ticks.append(v)
        e += 1
    return ticks


def label(v):
    return f"{v:g}"


def main():
    rows = []
    with open(sys.argv[1]) as f:
        for line in f:
            name, kind, minutes, err = line.rstrip("\n").split("\t")
            rows.append((name, kind, float(minutes), float(err)))
    w, h, ml, mr, mt, mb = 640, 420, 70, 20, 40, 55
    xs = [r[2] for r in rows]
    ys = [r[3] for r in rows]
    # Axis ranges: the 1-2-5 values just outside the data.
    def outer(lo, hi):
        cands = []
        for e in range(-4, 6):
            for m in (1, 2, 5):
                cands.append(m * 10**e)
        lo_r = max(c for c in cands if c <= lo)
        hi_r = min(c for c in cands if c >= hi)
        return lo_r, hi_r

    xlo, xhi = outer(min(xs), max(xs))
    ylo, yhi = outer(min(ys), max(ys))

    def px(x):
        return ml + (w - ml - mr) * (math.log10(x) - math.log10(xlo)) / (
            math.log10(xhi) - math.log10(xlo))

    def py(y):
        return h - mb - (h - mt - mb) * (math.log10(y) - math.log10(ylo)) / (
            math.log10(yhi) - math.log10(ylo))

    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" '
           f'font-family="sans-serif" font-size="12">',
           f'<rect width="{w}" height="{h}" fill="white"/>',
           f'<text x="{w/2}" y="20" text-anchor="middle" font-size="14">'
           'Work-volume tool position error after the fit against cell time</text>']
    for t in round_ticks(xlo, xhi):
        out.append(f'<line x1="{px(t):.1f}" y1="{mt}" x2="{px(t):.1f}" y2="{h-mb}" stroke="#ddd"/>')
        out.append(f'<text x="{px(t):.1f}" y="{h-mb+16}" text-anchor="middle">{label(t)}</text>')
    for t in round_ticks(ylo, yhi):
        out.append(f'<line x1="{ml}" y1="{py(t):.1f}" x2="{w-mr}" y2="{py(t):.1f}" stroke="#ddd"/>')
        out.append(f'<text x="{ml-6}" y="{py(t)+4:.1f}" text-anchor="end">{label(t)}</text>')
    out.append(f'<rect x="{ml}" y="{mt}" width="{w-ml-mr}" height="{h-mt-mb}" fill="none" '
               'stroke="black"/>')
    out.append(f'<text x="{(ml+w-mr)/2}" y="{h-12}" text-anchor="middle">'
               'cell time: moves, dwells and bar swaps (min, log scale)</text>')
    out.append(f'<text transform="translate(16,{(mt+h-mb)/2}) rotate(-90)" text-anchor="middle">'
               'RMS tool position error, compensated (mm, log scale)</text>')
    styles = {"grid": ("#1f77b4", "square"), "optimal": ("#d62728", "circle")}
    for kind, (colour, marker) in styles.items():
        pts = sorted((r for r in rows if r[1] == kind), key=lambda r: r[2])
        if not pts:
            continue
        if len(pts) > 1:
            path = " ".join(f"{px(r[2]):.1f},{py(r[3]):.1f}" for r in pts)
            out.append(f'<polyline points="{path}" fill="none" stroke="{colour}" '
                       'stroke-width="1.5"/>')
        for r in pts:
            x, y = px(r[2]), py(r[3])
            if marker == "circle":
                out.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="4" fill="{colour}"/>')
            else:
                out.append(f'<rect x="{x-4:.1f}" y="{y-4:.1f}" width="8" height="8" '
                           f'fill="{colour}"/>')
            out.append(f'<text x="{x+6:.1f}" y="{y-6:.1f}" font-size="10" fill="{colour}">'
                       f'{r[0]}</text>')
    lx, ly = w - mr - 170, mt + 14
    out.append(f'<rect x="{lx-4}" y="{ly-12}" width="170" height="40" fill="white" stroke="#999"/>')
    out.append(f'<rect x="{lx}" y="{ly-8}" width="8" height="8" fill="{styles["grid"][0]}"/>')
    out.append(f'<text x="{lx+14}" y="{ly}">grid plans (cell.json grid)</text>')
    out.append(f'<circle cx="{lx+4}" cy="{ly+14}" r="4" fill="{styles["optimal"][0]}"/>')
    out.append(f'<text x="{lx+14}" y="{ly+18}">optimal plans (budget, min)</text>')
    out.append("</svg>")
    with open(sys.argv[2], "w") as f:
        f.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
