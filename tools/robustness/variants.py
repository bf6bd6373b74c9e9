"""The variants of a real walk (issue 37): what a phone, a messenger or an editor does to a video.

Each variant is made from the original with ffmpeg and says how its clock and its sides map
back to the original's: `offset_s` is added to a variant's times (a cut start), `mirrored`
exchanges left and right, `scale` is the variant's width over the original's (pixel lengths).
"""
import dataclasses
import pathlib
import subprocess


@dataclasses.dataclass
class Variant:
    name: str
    what: str
    suffix: str
    args: list
    offset_s: float = 0.0
    mirrored: bool = False
    # Variant width / original width, for lengths in pixels; None: read from the output.
    scale: float = 1.0


def catalogue(duration_s, height):
    """Every variant of the full matrix, in the order of the table."""
    x264 = ["-c:v", "libx264", "-pix_fmt", "yuv420p", "-preset", "veryfast"]
    # Heights keep the aspect; -2 keeps the width even, as encoders need.
    scaled = lambda h: ["-vf", f"scale=-2:{h}"]  # noqa: E731
    cut = max(duration_s - 2.0, 0.5)
    return [
        Variant("crf18", "H.264 CRF 18 (visually lossless)", ".mp4", x264 + ["-crf", "18"]),
        Variant("crf23", "H.264 CRF 23 (ffmpeg's default)", ".mp4", x264 + ["-crf", "23"]),
        Variant("crf28", "H.264 CRF 28 (a messenger's copy)", ".mp4", x264 + ["-crf", "28"]),
        Variant("hevc_mov", "HEVC in .mov (an iPhone)", ".mov",
                ["-c:v", "libx265", "-crf", "23", "-preset", "fast", "-tag:v", "hvc1",
                 "-pix_fmt", "yuv420p", "-x265-params", "log-level=error"]),
        # An iPhone's default since the iPhone 12: 10-bit HEVC in HLG. gait converts it back to
        # standard range (colour.rs); decoded as standard video it is washed out and dark.
        Variant("hdr_hlg_mov", "HDR: 10-bit HEVC in HLG, .mov (an iPhone's default)", ".mov",
                ["-vf", "zscale=tin=bt709:min=bt709:pin=bt709:t=arib-std-b67:m=bt2020nc:p=bt2020:r=tv,"
                        "format=yuv420p10le",
                 "-c:v", "libx265", "-crf", "23", "-preset", "fast", "-tag:v", "hvc1",
                 "-x265-params", "log-level=error", "-color_trc", "arib-std-b67",
                 "-color_primaries", "bt2020", "-colorspace", "bt2020nc"]),
        Variant("vp9_webm", "VP9 in .webm (a browser recording)", ".webm",
                ["-c:v", "libvpx-vp9", "-crf", "32", "-b:v", "0", "-deadline", "realtime",
                 "-cpu-used", "8", "-row-mt", "1"]),
        Variant("fps60_dup", "60 fps, frames duplicated", ".mp4", ["-vf", "fps=60"] + x264 + ["-crf", "18"]),
        Variant("fps60_interp", "60 fps, motion-interpolated (minterpolate)", ".mp4",
                ["-vf", "minterpolate=fps=60:mi_mode=mci:mc_mode=aobmc"] + x264 + ["-crf", "18"]),
        Variant("fps25", "25 fps, frames dropped", ".mp4", ["-vf", "fps=25"] + x264 + ["-crf", "18"]),
        Variant("720p", "720 px high", ".mp4", scaled(720) + x264 + ["-crf", "18"], scale=None),
        Variant("480p", "480 px high", ".mp4", scaled(480) + x264 + ["-crf", "18"], scale=None),
        Variant("4k", "2160 px high (upscaled)", ".mp4", scaled(2160) + x264 + ["-crf", "18"], scale=None),
        Variant("mirrored", "mirrored left-right", ".mp4", ["-vf", "hflip"] + x264 + ["-crf", "18"],
                mirrored=True),
        Variant("bright", "brightness +0.08, contrast x1.2", ".mp4",
                ["-vf", "eq=brightness=0.08:contrast=1.2"] + x264 + ["-crf", "18"]),
        Variant("noise", "sensor-like noise (temporal, strength 10)", ".mp4",
                ["-vf", "noise=alls=10:allf=t"] + x264 + ["-crf", "18"]),
        # A phone's .mov: the declared rate is its 1/600 s timescale, frame times up to 7 ms off
        # a constant rate, and every other frame of 100-139 missing (dim light); gait resamples
        # such a video to the camera's constant rate (frame_timing.rs). The times assume a 30 fps original.
        Variant("phone_vfr", "a phone's variable frame rate (.mov, 1/600 s, frames missing)", ".mov",
                ["-vf", "settb=1/600,setpts='N*20+round(4*sin(N*1.7))',"
                        "select='not(between(n,100,139))+not(mod(n,2))'",
                 "-fps_mode", "passthrough", "-enc_time_base", "1/600",
                 "-video_track_timescale", "600"] + x264 + ["-crf", "18"]),
        Variant("cut", "first and last second cut", ".mp4",
                ["-ss", "1", "-t", f"{cut:.3f}"] + x264 + ["-crf", "18"], offset_s=1.0),
    ]


# The bounded matrix of tools/test.sh: the visually lossless re-encode that tipped every
# decision before issue 37's work, and ffmpeg's default CRF 23, where the subject pass used to
# link the walker's sightings differently. The frame-rate changes and the mirror still tip
# (BENCHMARKS.md, "Robustness"); the full matrix runs them.
QUICK = ["crf18", "crf23"]


def make(original, v, folder):
    """The variant's video in `folder` (made once; an existing one is reused)."""
    out = pathlib.Path(folder) / f"{v.name}{v.suffix}"
    if out.exists() and out.stat().st_size > 0:
        return out
    tmp = out.with_name(f".{out.name}.partial{v.suffix}")
    # -ss before -i would seek on key frames; after it, the cut is exact to the frame.
    head, tail = (v.args[:4], v.args[4:]) if v.name == "cut" else ([], v.args)
    cmd = ["ffmpeg", "-v", "error", "-y", "-i", str(original)] + head + ["-an"] + tail + [str(tmp)]
    subprocess.run(cmd, check=True)
    tmp.rename(out)
    return out


def probe(path):
    """(width, height, fps, frames) of a video, by ffprobe."""
    out = subprocess.run(
        ["ffprobe", "-v", "error", "-select_streams", "v:0", "-count_packets", "-show_entries",
         "stream=width,height,r_frame_rate,nb_read_packets", "-of", "csv=p=0", str(path)],
        check=True, capture_output=True, text=True).stdout.strip().split(",")
    num, den = out[2].split("/")
    return int(out[0]), int(out[1]), float(num) / float(den), int(out[3])
