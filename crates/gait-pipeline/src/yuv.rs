//! 4:2:0 YUV frames turned into RGB exactly as ffmpeg's `-pix_fmt rgb24` does.
//!
//! Most videos are 8-bit 4:2:0 (`yuv420p`), and ffmpeg converts them to rgb24 with swscale's
//! special converter: each 2 x 2 block shares its chroma sample (no interpolation), and the
//! sums are 16-bit fixed point (`pmulhw`: the high half of a signed product). Taking the frames
//! from ffmpeg as yuv420p (half the bytes of rgb24 through the socket, and no conversion in
//! ffmpeg) and converting them here gives the same bytes for less CPU (BENCHMARKS.md, issue
//! 40). Each input's first frame is sent both ways and compared (video_decoder.rs), so an
//! ffmpeg that converts otherwise (another version, swscale's plain-C converter on a CPU
//! without its SIMD code) costs the saving, never the results: its frames come as rgb24.

use std::mem::MaybeUninit;

/// The fixed-point coefficients of one colour matrix and range, as swscale derives them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Yuv420 {
    y_offset: i32,
    y_coeff: i32,
    v_red: i32,
    u_blue: i32,
    u_green: i32,
    v_green: i32,
}

/// swscale's inverse matrices in 16.16 fixed point (`ff_yuv2rgb_coeffs`): red from V, blue
/// from U, green from U, green from V (the last two subtracted).
fn matrix(color_space: Option<&str>) -> Option<[i64; 4]> {
    Some(match color_space.unwrap_or("unknown") {
        "bt709" => [117489, 138438, 13975, 34925],
        // What swscale takes for an unlabelled video: ITU-R BT.601.
        "unknown" | "bt470bg" | "smpte170m" => [104597, 132201, 25675, 53279],
        "fcc" => [104448, 132798, 24759, 53109],
        "smpte240m" => [117579, 136230, 16907, 35559],
        "bt2020nc" | "bt2020c" => [110013, 140363, 12277, 42626],
        _ => return None,
    })
}

/// A 16.16 value times 2^13, rounded into an i16 (swscale's `roundToInt16`).
fn to_i16(v: i64) -> i32 {
    ((v * (1 << 13) + (1 << 15)) >> 16).clamp(i16::MIN as i64, i16::MAX as i64) as i32
}

impl Yuv420 {
    /// The conversion of a `yuv420p` stream with ffprobe's `color_space` and `color_range`, when
    /// this module knows it (`None`: the frames are taken as rgb24 from ffmpeg).
    /// swscale converts only frames of even height this way.
    pub(crate) fn of_stream(
        pixel_format: Option<&str>,
        color_space: Option<&str>,
        color_range: Option<&str>,
        (width, height): (u32, u32),
    ) -> Option<Self> {
        if pixel_format != Some("yuv420p") || width % 2 == 1 || height % 2 == 1 {
            return None;
        }
        let matrix = matrix(color_space)?;
        // Limited range stretches luma 16-235 to 0-255; full range takes it as it is and
        // narrows the chroma terms to 224/255 instead.
        let (y_scale, y_offset, chroma_scale) = match color_range.unwrap_or("unknown") {
            "tv" | "unknown" => ((1i64 << 16) * 255 / 219, 16i64 << 16, 255),
            "pc" => (1 << 16, 0, 224),
            _ => return None,
        };
        let [red, blue, green_u, green_v] = matrix.map(|k| k * chroma_scale / 255);
        Some(Yuv420 {
            y_offset: ((y_offset * 8 + (1 << 15)) >> 16) as i32,
            y_coeff: to_i16(y_scale),
            v_red: to_i16(red),
            u_blue: to_i16(blue),
            u_green: to_i16(-green_u),
            v_green: to_i16(-green_v),
        })
    }

    /// Bytes of one `width` x `height` frame in yuv420p: the luma plane, then the two chroma
    /// planes at half size, rounded up.
    pub(crate) fn frame_len(width: usize, height: usize) -> usize {
        width * height + 2 * width.div_ceil(2) * height.div_ceil(2)
    }

    /// Converts one yuv420p frame (`src`, [`Self::frame_len`] bytes) into rgb24, appended to
    /// `out`.
    pub(crate) fn convert(&self, src: &[u8], width: usize, height: usize, out: &mut Vec<u8>) {
        let (cw, ch) = (width.div_ceil(2), height.div_ceil(2));
        let (luma, chroma) = src.split_at(width * height);
        let (u_plane, v_plane) = chroma.split_at(cw * ch);
        let len = width * height * 3;
        // Written in place, not zeroed first nor copied: a frame is megabytes.
        out.reserve(len);
        let frame = Frame {
            luma,
            u_plane,
            v_plane,
            width,
            out: &mut out.spare_capacity_mut()[..len],
        };
        // The rows cover the output whole (asserted), and `rows_of` writes every byte of its
        // rows (whole blocks, then the rest pixel by pixel).
        assert_eq!(rows(self, frame), len, "every row converted");
        // SAFETY: the `len` bytes after the vector's length were written just above.
        unsafe { out.set_len(out.len() + len) };
    }
}

/// One yuv420p frame's planes and the rgb24 output it is written to, not yet initialised.
struct Frame<'a> {
    luma: &'a [u8],
    u_plane: &'a [u8],
    v_plane: &'a [u8],
    width: usize,
    out: &'a mut [MaybeUninit<u8>],
}

/// [`rows_of`] in the widest registers the CPU has (the same integer operations: the same
/// bytes): the bytes written.
fn rows(c: &Yuv420, frame: Frame) -> usize {
    #[cfg(target_arch = "x86_64")]
    if is_x86_feature_detected!("avx512bw") {
        // SAFETY: the CPU has the features the function is compiled for.
        return unsafe { rows_avx512(c, frame) };
    }
    #[cfg(target_arch = "x86_64")]
    if is_x86_feature_detected!("avx2") {
        // SAFETY: as above.
        return unsafe { rows_avx2(c, frame) };
    }
    rows_of(c, frame)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512bw")]
unsafe fn rows_avx512(c: &Yuv420, frame: Frame) -> usize {
    rows_of(c, frame)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn rows_avx2(c: &Yuv420, frame: Frame) -> usize {
    rows_of(c, frame)
}

/// Every row of `frame`, two luma rows per chroma row: the bytes written.
#[inline(always)]
fn rows_of(c: &Yuv420, frame: Frame) -> usize {
    let Frame {
        luma,
        u_plane,
        v_plane,
        width,
        out,
    } = frame;
    let cw = width.div_ceil(2);
    let mut terms = [vec![0i32; cw], vec![0i32; cw], vec![0i32; cw]];
    let pairs = u_plane
        .chunks_exact(cw)
        .zip(v_plane.chunks_exact(cw))
        .zip(luma.chunks(2 * width))
        .zip(out.chunks_mut(2 * width * 3));
    let mut written = 0;
    for (((u_row, v_row), luma), out) in pairs {
        chroma_terms(c, u_row, v_row, &mut terms);
        for (luma, out) in luma.chunks(width).zip(out.chunks_mut(3 * width)) {
            row(c, luma, &terms, out);
        }
        written += out.len();
    }
    written
}

/// A chroma row's red, green and blue terms, one per chroma sample.
type Terms = [Vec<i32>; 3];

/// Pixels in a block of [`row`]: its planes stay in the first-level cache.
const BLOCK: usize = 64;

/// Each chroma sample's red, green and blue terms; in fixed-size chunks, the rest one by one.
#[inline(always)]
fn chroma_terms(c: &Yuv420, u_row: &[u8], v_row: &[u8], [red, green, blue]: &mut Terms) {
    const N: usize = BLOCK / 2;
    // Wrapping arithmetic, which cannot wrap here (8-bit input, 14-bit coefficients): the dev
    // build's overflow checks would keep the loops from being vectorised.
    let terms = |u: u8, v: u8| {
        let (u, v) = (
            (u as i32 * 8).wrapping_sub(1024),
            (v as i32 * 8).wrapping_sub(1024),
        );
        let term = |x: i32, k: i32| x.wrapping_mul(k) >> 16;
        let green = term(u, c.u_green).wrapping_add(term(v, c.v_green));
        [term(v, c.v_red), green, term(u, c.u_blue)]
    };
    let whole = u_row.len() / N * N;
    for k in (0..whole).step_by(N) {
        let u: &[u8; N] = u_row[k..k + N].try_into().expect("a chunk");
        let v: &[u8; N] = v_row[k..k + N].try_into().expect("a chunk");
        let r: &mut [i32; N] = (&mut red[k..k + N]).try_into().expect("a chunk");
        let g: &mut [i32; N] = (&mut green[k..k + N]).try_into().expect("a chunk");
        let b: &mut [i32; N] = (&mut blue[k..k + N]).try_into().expect("a chunk");
        for i in 0..N {
            [r[i], g[i], b[i]] = terms(u[i], v[i]);
        }
    }
    for i in whole..u_row.len() {
        [red[i], green[i], blue[i]] = terms(u_row[i], v_row[i]);
    }
}

/// One row of pixels, every byte of `out` written: whole blocks through fixed-size loops the
/// compiler vectorises, the rest pixel by pixel.
#[inline(always)]
fn row(c: &Yuv420, luma: &[u8], terms: &Terms, out: &mut [MaybeUninit<u8>]) {
    let whole = luma.len() / BLOCK * BLOCK;
    let (blocks, rest) = out.split_at_mut(3 * whole);
    let chunks = luma
        .chunks_exact(BLOCK)
        .zip(blocks.chunks_exact_mut(3 * BLOCK));
    for (k, (luma, out)) in chunks.enumerate() {
        let half = k * BLOCK / 2..(k + 1) * BLOCK / 2;
        block(
            c,
            luma.try_into().expect("a block"),
            terms
                .each_ref()
                .map(|t| t[half.clone()].try_into().expect("a block")),
            out.try_into().expect("a block"),
        );
    }
    for ((i, &y), px) in luma
        .iter()
        .enumerate()
        .skip(whole)
        .zip(rest.chunks_exact_mut(3))
    {
        let y = luma_term(c, y);
        for (v, t) in px.iter_mut().zip(terms) {
            v.write(channel(y, t[i / 2]));
        }
    }
}

/// A pixel's channel: its luma term plus its chroma term, clamped to 8 bits. The sum stays
/// far inside 16 bits for 8-bit input, so swscale's saturating adds never saturate.
#[inline(always)]
fn channel(luma: i32, chroma: i32) -> u8 {
    luma.wrapping_add(chroma).clamp(0, 255) as u8
}

#[inline(always)]
fn luma_term(c: &Yuv420, y: u8) -> i32 {
    ((y as i32 * 8).wrapping_sub(c.y_offset)).wrapping_mul(c.y_coeff) >> 16
}

#[inline(always)]
fn block(
    c: &Yuv420,
    luma: &[u8; BLOCK],
    terms: [&[i32; BLOCK / 2]; 3],
    out: &mut [MaybeUninit<u8>; 3 * BLOCK],
) {
    let mut y = [0i32; BLOCK];
    for i in 0..BLOCK {
        y[i] = luma_term(c, luma[i]);
    }
    let mut planes = [[0u8; BLOCK]; 3];
    for (plane, t) in planes.iter_mut().zip(terms) {
        for j in 0..BLOCK / 2 {
            plane[2 * j] = channel(y[2 * j], t[j]);
            plane[2 * j + 1] = channel(y[2 * j + 1], t[j]);
        }
    }
    let [r, g, b] = &planes;
    for i in 0..BLOCK {
        out[3 * i].write(r[i]);
        out[3 * i + 1].write(g[i]);
        out[3 * i + 2].write(b[i]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every Y, U and V combination (a 4096 x 4096 frame: each 2 x 2 block one chroma pair,
    /// 64 blocks per pair for the 256 luma values) converted by ffmpeg and here, for each
    /// colour matrix and range this module knows. On x86-64, where swscale's converter is
    /// SIMD code; its plain-C fallback (other CPUs, `-cpuflags 0`) rounds otherwise, and there
    /// the decoder's check finds the first frame different and the frames come as rgb24.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn every_value_converts_as_ffmpeg_converts() {
        let n = 4096;
        let mut src = vec![0u8; Yuv420::frame_len(n, n)];
        let (luma, chroma) = src.split_at_mut(n * n);
        let (u_plane, v_plane) = chroma.split_at_mut(n * n / 4);
        for block in 0..(n / 2) * (n / 2) {
            let (pair, y0) = (block / 64, (block % 64) * 4);
            u_plane[block] = (pair / 256) as u8;
            v_plane[block] = (pair % 256) as u8;
            let (by, bx) = (block / (n / 2), block % (n / 2));
            for (k, (dy, dx)) in [(0, 0), (0, 1), (1, 0), (1, 1)].into_iter().enumerate() {
                luma[(2 * by + dy) * n + 2 * bx + dx] = (y0 + k) as u8;
            }
        }
        let dir = tempfile::tempdir().unwrap();
        let raw = dir.path().join("all.yuv");
        std::fs::write(&raw, &src).unwrap();
        let spaces = [
            "bt709",
            "unknown",
            "bt470bg",
            "smpte170m",
            "fcc",
            "smpte240m",
            "bt2020nc",
        ];
        let cases = spaces
            .iter()
            .map(|s| (*s, "tv"))
            .chain([("bt709", "pc"), ("unknown", "pc")]);
        for (space, range) in cases {
            let mut cmd = std::process::Command::new("ffmpeg");
            cmd.args(["-v", "error", "-f", "rawvideo", "-pix_fmt", "yuv420p", "-s"])
                .arg(format!("{n}x{n}"))
                .args(["-color_range", range]);
            if space != "unknown" {
                cmd.args(["-colorspace", space]);
            }
            let out = cmd
                .arg("-i")
                .arg(&raw)
                .args(["-f", "rawvideo", "-pix_fmt", "rgb24", "-"])
                .output()
                .expect("ffmpeg (tools/setup.sh installs it)");
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            let c = Yuv420::of_stream(Some("yuv420p"), Some(space), Some(range), (4, 4)).unwrap();
            let mut ours = Vec::new();
            c.convert(&src, n, n, &mut ours);
            let differ = ours
                .chunks_exact(3)
                .zip(out.stdout.chunks_exact(3))
                .filter(|(a, b)| a != b)
                .count();
            assert_eq!(
                differ, 0,
                "{space}, {range}: pixels that differ from ffmpeg's"
            );
        }
    }
}
