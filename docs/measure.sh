#!/bin/sh
# Regenerates the measurements committed under docs/: the thesis tables (docs/bench/) and one
# accuracy-vs-time sweep per thesis scene (docs/sweeps/). Run from the project root on a quiet
# machine, after `cargo build --release`: `sh docs/measure.sh` (about 35 minutes on 2 cores), or
# `sh docs/measure.sh sweeps` for the sweeps alone.
set -e
H=./target/release/hyrt
[ "${1:-}" = sweeps ] || $H bench --runs 10 --out docs/bench
# The light maps' resolution, which sets the hybrid's default (docs/results.md, "Map resolution").
for s in cornell-bunny-mirror office conference; do
  $H sweep scenes/$s.toml --runs 7 --out docs/sweeps/$s-map-res --knob shadow-map-res=512,1024,2048,4096
done
$H sweep scenes/cornell-bunny-mirror.toml --runs 5 --out docs/sweeps/cornell-bunny-mirror \
  --knob shadow-map=cube,paraboloid --knob shadow-map-res=256,512,1024,2048 --knob borders=laplacian,depth,both
$H sweep scenes/office.toml --runs 5 --out docs/sweeps/office --base "--preset hybrid --shadow-map paraboloid" \
  --knob shadow-map-res=512,1024,2048 --knob tess=2,8,inf --knob dilate=0,1
$H sweep scenes/conference.toml --runs 3 --out docs/sweeps/conference \
  --knob shadow-map-res=512,1024,2048 --knob bias=0.5,1,2 --knob borders=laplacian,depth
# Border pairs made by ambiguity alone: whole rays or their triangles, against the bias.
for s in cornell-bunny-mirror office conference; do
  $H sweep scenes/$s.toml --runs 5 --out docs/sweeps/$s-ambiguous --knob ambiguous=rays,triangles --knob bias=0.5,1,2
done
# VPL maps, 45 VPLs, against VPL rays with the same direct light: format x resolution x filter.
for s in cornell-bunny-mirror office conference; do
  $H sweep scenes/$s.toml --runs 3 --out docs/sweeps/$s-vpl-maps \
    --base "--preset hybrid --indirect maps --vpls 45" --reference "--preset hybrid --indirect rays --vpls 45" \
    --knob vpl-format=planes,depth16 --knob vpl-map-res=256,512,1024 --knob vpl-filter=texel,bilinear
done
# Many VPLs: 256 on the conference room, interleaved, against all 256 by maps and by rays.
$H sweep scenes/conference.toml --runs 5 --out docs/sweeps/conference-256-vpls \
  --base "--preset hybrid --indirect maps --vpls 256" --reference "--preset hybrid --indirect maps --vpls 256 --interleave 1" \
  --knob interleave=1,2,4 --knob vpl-map-res=256,512
$H sweep scenes/conference.toml --runs 3 --out docs/sweeps/conference-256-vpls-vs-reference \
  --base "--preset hybrid --indirect maps --vpls 256" --reference "--preset reference --indirect rays --vpls 256" \
  --knob interleave=1,2,4 --knob vpl-map-res=256,512
