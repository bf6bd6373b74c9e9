#!/usr/bin/env bash
# Writes the seeds of the `video_stream` fuzz target (fuzz/seeds/video_stream/*.rec): real runs of
# ffprobe and ffmpeg, as gait runs them, recorded by `gait-fuzz record-video`. Frames are kept tiny
# (16x12 to 32x18) so that mutations land on the description and the stream's length as often as on
# pixels. Run from the repository root: bash tools/fuzz/video_stream_seeds.sh
set -euo pipefail
out=fuzz/seeds/video_stream
sample=${SAMPLE_VIDEO:-../shared/data/sports2d-demo.mp4}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cargo build -q -p gait-fuzz
record() { target/debug/gait-fuzz record-video "$tmp/$1" "$out/${1%.*}.rec"; }
mkdir -p "$out"
ff() { ffmpeg -v error -y "$@"; }

# A clean H.264 clip: 4 frames of testsrc.
ff -f lavfi -i testsrc=size=16x12:rate=30 -frames:v 4 -c:v libx264 -pix_fmt yuv420p "$tmp/testsrc_16x12.mp4"
record testsrc_16x12.mp4
# The sample's walker (frames 60-62), scaled down.
ff -i "$sample" -an -vf "select=between(n\,60\,62),setpts=N/FRAME_RATE/TB,scale=32:18" -c:v libx264 -pix_fmt yuv420p "$tmp/sample_walker_32x18.mp4"
record sample_walker_32x18.mp4
# A phone clip held upright: rotation in the side data, frames turned by ffmpeg (12x16).
ff -i "$tmp/testsrc_16x12.mp4" -c copy -metadata:s:v:0 rotate=90 "$tmp/testsrc_rotated.mp4"
record testsrc_rotated.mp4
# A phone's variable frame rate behind a preview stream and audio: frames 3-6 of 10 with every
# other one missing, the 16x12 stream second (the analysed one), a 8x6 preview first.
ff -f lavfi -i sine=d=0.4 -f lavfi -i testsrc=size=8x6:rate=30 -f lavfi -i testsrc=size=16x12:rate=30 \
  -filter_complex "[2:v]select='not(between(n,3,6))+not(mod(n,2))'[v]" -map 0 -map 1:v -map "[v]" \
  -frames:v:0 10 -frames:v:1 8 -fps_mode:v:1 passthrough -c:v mjpeg -t 0.34 "$tmp/vfr_two_streams.mkv"
record vfr_two_streams.mkv
# Its description alone, for the ffprobe_json target.
ffprobe -v error -select_streams V -show_entries stream=index,codec_type,width,height,r_frame_rate,nb_frames:stream_disposition=attached_pic:stream_side_data=rotation:packet=stream_index,pts_time \
  -of json=compact=1 "$tmp/vfr_two_streams.mkv" > fuzz/seeds/ffprobe_json/vfr_two_streams.json
# A damaged MJPEG clip: bytes flipped after the header, so ffmpeg reports decoding errors.
ff -f lavfi -i testsrc=size=16x12:rate=30 -frames:v 6 -c:v mjpeg "$tmp/damaged_mjpeg.avi"
python3 - "$tmp/damaged_mjpeg.avi" <<'PY'
import sys
p = sys.argv[1]
b = bytearray(open(p, "rb").read())
for i in range(2048, len(b), 97):
    b[i] ^= 0xFF
open(p, "wb").write(b)
PY
record damaged_mjpeg.avi
ls -l "$out"
