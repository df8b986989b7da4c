#!/usr/bin/env bash
# An SVG plot of tools/bench/long_run.sh's status.csv against elapsed time, four panels: the map's
# keyframes, its points, the RSS of every process, and the times (frontend per frame p50, local mapper
# per keyframe p50, map save p50). Plain awk, no plotting package:
#   tools/bench/long_run_plot.sh OUT_DIR/status.csv > OUT_DIR/long_run.svg
set -euo pipefail
csv=${1:?usage: long_run_plot.sh STATUS_CSV > FILE.svg}
[[ -s $csv ]] || { echo "long_run_plot.sh: '$csv' is missing or empty" >&2; exit 2; }
head -n 1 "$csv" | grep -q '^elapsed_s,component,pid,rss_mib,' ||
  { echo "long_run_plot.sh: '$csv': not a long_run.sh status.csv (header)" >&2; exit 2; }
awk -F, '
  function series(panel, label, x, y) {
    if (y == "") return
    if (!((panel, label) in has)) { has[panel, label] = 1; labels[panel, ++nlabels[panel]] = label }
    k = ++npts[panel, label]; px[panel, label, k] = x; py[panel, label, k] = y
    if (y + 0 > ymax[panel]) ymax[panel] = y + 0
    if (x + 0 > xmax) xmax = x + 0
  }
  NR == 1 { next }
  {
    if ($2 == "local_mapper") { series(1, "map keyframes", $1, $7); series(2, "map points", $1, $8)
                                series(4, "mapper per keyframe p50", $1, $11); series(4, "map save p50", $1, $12) }
    if ($2 == "frontend") series(4, "frontend per frame p50", $1, $9)
    series(3, $2, $1, $4)
  }
  END {
    W = 900; H = 230; L = 80; R = 230; T = 30; B = 40
    split("map keyframes|map points|RSS (MiB)|time (ms)", title, "|")
    split("#1f77b4 #d62728 #2ca02c #ff7f0e #9467bd #8c564b #e377c2 #7f7f7f #17becf", colour, " ")
    if (xmax <= 0) xmax = 1
    printf "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\"", W, 4 * H
    printf " font-family=\"sans-serif\" font-size=\"12\">\n"
    printf "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n"
    for (p = 1; p <= 4; ++p) {
      y0 = (p - 1) * H; pw = W - L - R; ph = H - T - B
      top = ymax[p] > 0 ? ymax[p] * 1.05 : 1
      printf "<text x=\"%d\" y=\"%d\" font-weight=\"bold\">%s</text>\n", L, y0 + 18, title[p]
      printf "<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"none\" stroke=\"#444\"/>\n", L, y0 + T, pw, ph
      for (g = 0; g <= 4; ++g) {
        gy = y0 + T + ph - g * ph / 4
        printf "<line x1=\"%d\" y1=\"%.1f\" x2=\"%d\" y2=\"%.1f\" stroke=\"#ddd\"/>\n", L, gy, L + pw, gy
        printf "<text x=\"%d\" y=\"%.1f\" text-anchor=\"end\">%.4g</text>\n", L - 6, gy + 4, g * top / 4
        gx = L + g * pw / 4
        printf "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">%.0f s</text>\n", gx, y0 + T + ph + 16, g * xmax / 4
      }
      for (s = 1; s <= nlabels[p]; ++s) {
        label = labels[p, s]; c = colour[(s - 1) % 9 + 1]; pts = ""
        for (k = 1; k <= npts[p, label]; ++k)
          pts = pts sprintf("%.1f,%.1f ", L + px[p, label, k] / xmax * pw, y0 + T + ph - py[p, label, k] / top * ph)
        printf "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"1.5\" points=\"%s\"/>\n", c, pts
        printf "<text x=\"%d\" y=\"%d\" fill=\"%s\">%s</text>\n", L + pw + 10, y0 + T + 14 * s, c, label
      }
    }
    printf "<text x=\"%d\" y=\"%d\" text-anchor=\"middle\">elapsed wall time</text>\n", L + (W - L - R) / 2, 4 * H - 6
    printf "</svg>\n"
  }' "$csv"
