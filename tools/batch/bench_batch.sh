#!/usr/bin/env bash
# Overhead of `gait batch` per video over a plain `gait run`: one clip of the sample (the whole
# walk, 140 frames) run three ways in each round, each into a fresh folder with its own cache
# so every run computes everything: plain `gait run`, a one-row study with `--executor local`,
# and the same with `--executor slurm --wait` on the one-node Slurm of tools/batch/slurm.sh.
#
# Usage: tools/batch/bench_batch.sh [ROUNDS]   (default 3)
set -euo pipefail
cd "$(dirname "$0")/../.."
source tools/setup.sh
set +e +o pipefail
rounds=${1:-3}
cargo build -q -p gait-cli
target/debug/gait models fetch blazepose >/dev/null 2>&1
eval "export $(bash tools/batch/slurm.sh up)"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
ffmpeg -v error -y -ss 1.9 -i data/sample/sports2d-demo.mp4 -frames:v 140 -an -c:v libx264 \
  -preset veryfast -pix_fmt yuv420p "$work/clip.mp4"
printf 'video,subject,session,view,prosthetic_side,config,set\nclip.mp4,S01,1,left,,,report.pdf=false\n' >"$work/study.csv"
now() { python3 -c "import time; print(time.time())"; }
echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores; $(date -u +%F)"
printf '| round | gait run (s) | batch local (s) | overhead (s) | batch slurm --wait (s) | overhead (s) |\n| --- | --- | --- | --- | --- | --- |\n'
for r in $(seq "$rounds"); do
  t0=$(now)
  target/debug/gait run --no-progress --input "$work/clip.mp4" --out "$work/plain$r" --set report.pdf=false >/dev/null 2>&1
  t1=$(now)
  target/debug/gait batch "$work/study.csv" --out "$work/local$r" >/dev/null 2>&1
  t2=$(now)
  target/debug/gait batch "$work/study.csv" --out "$work/slurm$r" --executor slurm --wait >/dev/null 2>&1
  t3=$(now)
  python3 -c "a,b,c,d=$t0,$t1,$t2,$t3; p=b-a; l=c-b; s=d-c; print(f'| $r | {p:.1f} | {l:.1f} | {l-p:+.1f} | {s:.1f} | {s-p:+.1f} |')"
done
