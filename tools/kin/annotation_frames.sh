#!/usr/bin/env bash
# Extract crops of the walking woman's lower legs and feet from the real sample video
# (data/sample/sports2d-demo.mp4, Sports2D project, BSD-3-Clause, (c) David Pagnon) for MANUAL, by-eye
# annotation of gait events (tests/data/sample-events/). Nothing here reads any pose-model output.
#
# Usage:
#   tools/kin/annotation_frames.sh [OUT_DIR]
#       Overview crops (default OUT_DIR /tmp/gait-annotation-frames); env FIRST / LAST (frame range,
#       inclusive, default 40..200), GROUP (frames per montage, default 8), VIDEO (input).
#       OUT_DIR/crops/frame_NNN.png   one 600x300 full-resolution crop per frame (knees to below the feet)
#       OUT_DIR/montage_NNN.png       GROUP consecutive crops starting at frame NNN, tiled 2 wide, row-major
#   tools/kin/annotation_frames.sh zoom FIRST LAST X Y [W H SCALE COLS GRID] [OUT_DIR]
#       Close-up of one foot: frames FIRST..LAST, the WxH region (default 240x240) whose top-left corner
#       is (X, Y) in video pixels, upscaled SCALE times (default 2, lanczos), tiled COLS wide (default 3),
#       with a GRID-pixel grid (video pixels, default 20).  Writes OUT_DIR/zoom_FIRST-LAST_X_Y_WxH.png.
#       The close-ups used for tests/data/sample-events were  W H SCALE COLS GRID =
#       240 240 2 3 20 (6 frames), 100 100 4 3 10 (6 frames) and 120 60 6 2 5 (8 frames).
#
# Frame numbers: every crop has its frame index drawn in its top-left corner. The text is drawn BEFORE the
# select filter, so it is the 0-based index of the frame in the input (ffmpeg's n), the index used in
# tests/data/sample-events/events.csv. Every crop also has a grid fixed to the image, so that a foot's
# position can be compared between frames; within one montage the crop window does not move.
set -euo pipefail

cd "$(dirname "$0")/../.."
VIDEO=${VIDEO:-data/sample/sports2d-demo.mp4}
FONT=${FONT:-/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf}
VW=1768 # video width (px)

label() { # drawtext filter putting the input frame index at (x, y), size s
    echo "drawtext=fontfile=$FONT:text='%{n}':x=$1:y=$2:fontsize=$3:fontcolor=yellow:box=1:boxcolor=black@0.7"
}

if [[ ${1:-} == zoom ]]; then
    shift
    a=$1 b=$2 zx=$3 zy=$4
    shift 4
    zw=240 zh=240 sc=2 cols=3 grid=20
    if (($# >= 5)); then zw=$1 zh=$2 sc=$3 cols=$4 grid=$5; shift 5; fi
    out=${1:-/tmp/gait-annotation-frames}
    n=$((b - a + 1)) rows=$(((b - a + cols) / cols))
    mkdir -p "$out"
    f="$out/zoom_${a}-${b}_${zx}_${zy}_${zw}x${zh}.png"
    fs=$((zh / 8)); ((fs < 8)) && fs=8
    vf="$(label "$zx" "$zy" "$fs")"
    vf+=",select=between(n\\,$a\\,$b),crop=$zw:$zh:$zx:$zy"
    vf+=",scale=$((zw * sc)):$((zh * sc)):flags=lanczos,drawgrid=w=$((grid * sc)):h=$((grid * sc)):t=1:c=white@0.3"
    vf+=",tile=${cols}x${rows}:nb_frames=$n:padding=4:color=red"
    ffmpeg -v error -y -i "$VIDEO" -vf "$vf" -frames:v 1 "$f"
    echo "$f"
    exit 0
fi

OUT=${1:-/tmp/gait-annotation-frames}
FIRST=${FIRST:-40}
LAST=${LAST:-200}
GROUP=${GROUP:-8}
W=600 # crop width (px, full resolution)
H=300 # crop height
Y=694 # crop top: knees to below the feet (the video is 994 px high)

# The walker's feet, by eye from a few full frames: x ~1520 at frame 50, ~110 at frame 190 (right to left).
walker_x() { awk -v n="$1" 'BEGIN { printf "%d", 1520 - 10.1 * (n - 50) }'; }

mkdir -p "$OUT/crops"
for ((g = FIRST; g <= LAST; g += GROUP)); do
    e=$((g + GROUP - 1))
    ((e > LAST)) && e=$LAST
    x=$(($(walker_x $(((g + e) / 2))) - W / 2))
    ((x < 0)) && x=0
    ((x > VW - W)) && x=$((VW - W))
    vf="$(label $((x + 8)) $((Y + 8)) 36),select=between(n\\,$g\\,$e),crop=$W:$H:$x:$Y"
    vf+=",drawgrid=w=50:h=50:t=1:c=white@0.25"
    ffmpeg -v error -y -i "$VIDEO" -vf "$vf" -fps_mode passthrough -start_number "$g" "$OUT/crops/frame_%03d.png"
    ffmpeg -v error -y -i "$VIDEO" -vf "$vf,tile=2x$(((GROUP + 1) / 2)):padding=4:color=red" -frames:v 1 \
        "$OUT/montage_$(printf %03d "$g").png"
done
echo "wrote $OUT/crops/frame_*.png and $OUT/montage_*.png" >&2
