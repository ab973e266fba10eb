#!/usr/bin/env python3
"""Plots the soak test's resident-memory curve as an SVG (no plotting library needed).

    ILLUME_SOAK_SECONDS=3600 cargo test --release -p illume-photon-stream --test soak \\
        -- --nocapture 2> soak.log
    python3 scripts/plot_soak.py soak.log docs/images/soak_memory.svg

Reads the lines `soak: t = T s, resident M MB, frames F` and draws resident memory [MB]
against time [min], with the warm-up end and the ±5 % band the test allows after it.
"""

import re
import sys


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: plot_soak.py SOAK_LOG OUT.svg")
    points = []
    with open(sys.argv[1], encoding="utf-8", errors="replace") as f:
        for line in f:
            m = re.search(r"soak: t =\s*([\d.]+) s, resident ([\d.]+) MB", line)
            if m:
                points.append((float(m.group(1)), float(m.group(2))))
    if len(points) < 2:
        sys.exit(f"plot_soak: fewer than two samples in {sys.argv[1]}")
    duration = points[-1][0]
    warm_up = min(duration * 0.25, 60.0)
    base = next(mb for t, mb in points if t >= warm_up)
    w, h, left, right, top, bottom = 720, 300, 60, 20, 30, 45
    t_max = duration / 60.0
    y_lo = 0.0
    y_hi = max(max(mb for _, mb in points), base * 1.05) * 1.25

    def x(t_min):
        return left + (w - left - right) * t_min / t_max

    def y(mb):
        return top + (h - top - bottom) * (1.0 - (mb - y_lo) / (y_hi - y_lo))

    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12">',
           f'<rect width="{w}" height="{h}" fill="white"/>',
           f'<text x="{left}" y="18">photon_stream soak: resident memory, {duration / 60:.0f} min, '
           f'{base:.1f} MB after warm-up (band: +5 %)</text>']
    out.append(f'<rect x="{x(warm_up / 60):.1f}" y="{y(base * 1.05):.1f}" width="{x(t_max) - x(warm_up / 60):.1f}" '
               f'height="{y(base) - y(base * 1.05):.1f}" fill="#d8f0d8"/>')
    for i in range(6):
        mb = y_lo + (y_hi - y_lo) * i / 5
        out.append(f'<line x1="{left}" x2="{w - right}" y1="{y(mb):.1f}" y2="{y(mb):.1f}" stroke="#ddd"/>')
        out.append(f'<text x="{left - 6}" y="{y(mb) + 4:.1f}" text-anchor="end">{mb:.0f}</text>')
    for i in range(7):
        t = t_max * i / 6
        out.append(f'<text x="{x(t):.1f}" y="{h - bottom + 16}" text-anchor="middle">{t:.0f}</text>')
    out.append(f'<text x="{(left + w - right) / 2}" y="{h - 8}" text-anchor="middle">time [min]</text>')
    out.append(f'<text x="14" y="{(top + h - bottom) / 2}" transform="rotate(-90 14 {(top + h - bottom) / 2})" '
               f'text-anchor="middle">resident [MB]</text>')
    path = " ".join(f"{x(t / 60):.1f},{y(mb):.1f}" for t, mb in points)
    out.append(f'<polyline points="{path}" fill="none" stroke="#1f5fbf" stroke-width="1.5"/>')
    out.append(f'<line x1="{x(warm_up / 60):.1f}" x2="{x(warm_up / 60):.1f}" y1="{top}" y2="{h - bottom}" '
               f'stroke="#888" stroke-dasharray="4 3"/>')
    out.append("</svg>")
    with open(sys.argv[2], "w", encoding="utf-8") as f:
        f.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
