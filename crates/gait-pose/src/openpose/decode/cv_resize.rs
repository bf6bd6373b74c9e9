//! OpenCV 4.10's `cv::resize` for the interpolations the OpenPose search uses
//! (INTER_CUBIC, INTER_LANCZOS4, INTER_AREA), on interleaved `f32` or `u8`
//! data, reproducing its arithmetic: `f32` to rounding, `u8` bit for bit
//! (11-bit fixed-point coefficients, and the float vertical pass OpenCV's
//! SIMD code uses for cubic `u8` on 8-element blocks).

/// Interpolation, as OpenCV's `INTER_*` flag.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interp {
    /// Bicubic with a = -0.75.
    Cubic,
    /// 8x8 Lanczos.
    Lanczos4,
    /// Pixel-area averaging when shrinking (a bilinear variant otherwise).
    Area,
}

/// Source and destination sizes with OpenCV's inverse scale factors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geometry {
    /// Source width and height.
    pub sw: usize,
    pub sh: usize,
    /// Destination width and height.
    pub dw: usize,
    pub dh: usize,
    inv_x: f64,
    inv_y: f64,
}

impl Geometry {
    /// `cv2.resize(src, (dw, dh))`: the mapping uses `dw / sw`.
    pub fn to_size(sw: usize, sh: usize, dw: usize, dh: usize) -> Self {
        Self {
            sw,
            sh,
            dw,
            dh,
            inv_x: dw as f64 / sw.max(1) as f64,
            inv_y: dh as f64 / sh.max(1) as f64,
        }
    }

    /// `cv2.resize(src, (0, 0), fx=f, fy=f)`: the size is `round(w * f)` and
    /// the mapping uses `1 / f` itself, not `w / dw`.
    pub fn by_factor(sw: usize, sh: usize, f: f64) -> Self {
        let round = |v: f64| v.round_ties_even().max(0.0) as usize;
        Self {
            sw,
            sh,
            dw: round(sw as f64 * f),
            dh: round(sh as f64 * f),
            inv_x: f,
            inv_y: f,
        }
    }

    fn is_empty(&self) -> bool {
        self.sw == 0 || self.sh == 0 || self.dw == 0 || self.dh == 0
    }
}

const COEF_BITS: i32 = 11;
const COEF_SCALE: f32 = (1 << COEF_BITS) as f32;

fn cubic_coeffs(x: f32) -> [f32; 4] {
    const A: f32 = -0.75;
    let c0 = ((A * (x + 1.0) - 5.0 * A) * (x + 1.0) + 8.0 * A) * (x + 1.0) - 4.0 * A;
    let c1 = ((A + 2.0) * x - (A + 3.0)) * x * x + 1.0;
    let c2 = ((A + 2.0) * (1.0 - x) - (A + 3.0)) * (1.0 - x) * (1.0 - x) + 1.0;
    [c0, c1, c2, 1.0 - c0 - c1 - c2]
}

fn lanczos4_coeffs(x: f32) -> [f32; 8] {
    const S45: f64 = std::f64::consts::FRAC_1_SQRT_2;
    // sin/cos of the eight taps as rotations of the first one (as OpenCV does,
    // so the coefficients round the same way).
    const CS: [[f64; 2]; 8] = [
        [1.0, 0.0],
        [-S45, -S45],
        [0.0, 1.0],
        [S45, -S45],
        [-1.0, 0.0],
        [S45, S45],
        [0.0, -1.0],
        [-S45, S45],
    ];
    let mut c = [0f32; 8];
    let mut sum = 0f32;
    let y0 = -((x + 3.0) as f64) * std::f64::consts::PI * 0.25;
    let (s0, c0) = (y0.sin(), y0.cos());
    for (i, ci) in c.iter_mut().enumerate() {
        let y0i = x + 3.0 - i as f32;
        *ci = if y0i.abs() >= 1e-6 {
            let y = -(y0i as f64) * std::f64::consts::PI * 0.25;
            ((CS[i][0] * s0 + CS[i][1] * c0) / (y * y)) as f32
        } else {
            1e30
        };
        sum += *ci;
    }
    let inv = 1.0 / sum;
    for ci in c.iter_mut() {
        *ci *= inv;
    }
    c
}

/// Per destination index: the first source tap (may be out of range) and
/// the `ksize` weights.
struct Taps {
    ksize: usize,
    first: Vec<isize>,
    weights: Vec<f32>,
}

fn taps(
    src_len: usize,
    dst_len: usize,
    inv_scale: f64,
    interp: Interp,
    clamp_linear: bool,
) -> Taps {
    let scale = 1.0 / inv_scale;
    let ksize = match interp {
        Interp::Cubic => 4,
        Interp::Lanczos4 => 8,
        Interp::Area => 2,
    };
    let half = (ksize / 2) as isize;
    let mut first = Vec::with_capacity(dst_len);
    let mut weights = Vec::with_capacity(dst_len * ksize);
    for d in 0..dst_len {
        let (mut s, mut f);
        if interp == Interp::Area {
            // OpenCV's "area" emulation when not shrinking: a bilinear variant.
            s = (d as f64 * scale).floor() as isize;
            f = ((d + 1) as f64 - (s + 1) as f64 * inv_scale) as f32;
            f = if f <= 0.0 { 0.0 } else { f - f.floor() };
            if clamp_linear {
                if s < 0 {
                    f = 0.0;
                    s = 0;
                }
                if s >= src_len as isize - 1 {
                    f = 0.0;
                    s = src_len as isize - 1;
                }
            }
        } else {
            let fx = ((d as f64 + 0.5) * scale - 0.5) as f32;
            s = fx.floor() as isize;
            f = fx - s as f32;
        }
        first.push(s - half + 1);
        match interp {
            Interp::Cubic => weights.extend_from_slice(&cubic_coeffs(f)),
            Interp::Lanczos4 => weights.extend_from_slice(&lanczos4_coeffs(f)),
            Interp::Area => weights.extend_from_slice(&[1.0 - f, f]),
        }
    }
    Taps {
        ksize,
        first,
        weights,
    }
}

fn clamp_index(i: isize, len: usize) -> usize {
    i.clamp(0, len as isize - 1) as usize
}

/// Resizes interleaved `f32` data with `cn` channels (zeros on a size mismatch).
pub fn resize_f32(src: &[f32], cn: usize, g: Geometry, interp: Interp) -> Vec<f32> {
    if g.is_empty() || cn == 0 || src.len() != g.sw * g.sh * cn {
        return vec![0.0; g.dw * g.dh * cn];
    }
    if g.sw == g.dw && g.sh == g.dh {
        return src.to_vec();
    }
    if interp == Interp::Area && g.inv_x <= 1.0 && g.inv_y <= 1.0 {
        return area_shrink(src, cn, g, |v: f32| v, |v: f32| v);
    }
    let tx = taps(g.sw, g.dw, g.inv_x, interp, true);
    let ty = taps(g.sh, g.dh, g.inv_y, interp, false);
    let k = tx.ksize;
    // Horizontal pass over every source row, then the vertical pass.
    let mut rows = vec![0f32; g.sh * g.dw * cn];
    for sy in 0..g.sh {
        let s = &src[sy * g.sw * cn..(sy + 1) * g.sw * cn];
        let out = &mut rows[sy * g.dw * cn..(sy + 1) * g.dw * cn];
        for dx in 0..g.dw {
            let w = &tx.weights[dx * k..(dx + 1) * k];
            for c in 0..cn {
                let mut v = 0f32;
                for (j, wj) in w.iter().enumerate() {
                    let sx = clamp_index(tx.first[dx] + j as isize, g.sw);
                    v += s[sx * cn + c] * wj;
                }
                out[dx * cn + c] = v;
            }
        }
    }
    let width = g.dw * cn;
    let mut dst = vec![0f32; g.dh * width];
    for dy in 0..g.dh {
        let w = &ty.weights[dy * k..(dy + 1) * k];
        let out = &mut dst[dy * width..(dy + 1) * width];
        for (j, wj) in w.iter().enumerate() {
            let sy = clamp_index(ty.first[dy] + j as isize, g.sh);
            let r = &rows[sy * width..(sy + 1) * width];
            for (o, v) in out.iter_mut().zip(r) {
                *o += v * wj;
            }
        }
    }
    dst
}

/// Resizes interleaved `u8` data with `cn` channels (zeros on a size mismatch).
pub fn resize_u8(src: &[u8], cn: usize, g: Geometry, interp: Interp) -> Vec<u8> {
    if g.is_empty() || cn == 0 || src.len() != g.sw * g.sh * cn {
        return vec![0; g.dw * g.dh * cn];
    }
    if g.sw == g.dw && g.sh == g.dh {
        return src.to_vec();
    }
    if interp == Interp::Area && g.inv_x <= 1.0 && g.inv_y <= 1.0 {
        let ix = (1.0 / g.inv_x).round_ties_even();
        let iy = (1.0 / g.inv_y).round_ties_even();
        let fast =
            (1.0 / g.inv_x - ix).abs() < f64::EPSILON && (1.0 / g.inv_y - iy).abs() < f64::EPSILON;
        if fast {
            return area_fast_u8(src, cn, g, ix as usize, iy as usize);
        }
        return area_shrink(
            src,
            cn,
            g,
            |v: u8| v as f32,
            |v: f32| v.round_ties_even().clamp(0.0, 255.0) as u8,
        );
    }
    let tx = taps(g.sw, g.dw, g.inv_x, interp, true);
    let ty = taps(g.sh, g.dh, g.inv_y, interp, false);
    let k = tx.ksize;
    let fixed = |w: &[f32]| -> Vec<i32> {
        w.iter()
            .map(|v| {
                (v * COEF_SCALE)
                    .round_ties_even()
                    .clamp(i16::MIN as f32, i16::MAX as f32) as i32
            })
            .collect()
    };
    let (ax, ay) = (fixed(&tx.weights), fixed(&ty.weights));
    let mut rows = vec![0i32; g.sh * g.dw * cn];
    for sy in 0..g.sh {
        let s = &src[sy * g.sw * cn..(sy + 1) * g.sw * cn];
        let out = &mut rows[sy * g.dw * cn..(sy + 1) * g.dw * cn];
        for dx in 0..g.dw {
            let w = &ax[dx * k..(dx + 1) * k];
            for c in 0..cn {
                let mut v = 0i32;
                for (j, wj) in w.iter().enumerate() {
                    let sx = clamp_index(tx.first[dx] + j as isize, g.sw);
                    v = v.wrapping_add(s[sx * cn + c] as i32 * wj);
                }
                out[dx * cn + c] = v;
            }
        }
    }
    let width = g.dw * cn;
    // OpenCV vectorises the cubic vertical pass in float on blocks of 8
    // (128-bit lanes of i16) and finishes the row in fixed point.
    let simd_end = if interp == Interp::Cubic {
        width / 8 * 8
    } else {
        0
    };
    let mut dst = vec![0u8; g.dh * width];
    for dy in 0..g.dh {
        let w = &ay[dy * k..(dy + 1) * k];
        let srows: Vec<&[i32]> = (0..k)
            .map(|j| {
                let sy = clamp_index(ty.first[dy] + j as isize, g.sh);
                &rows[sy * width..(sy + 1) * width]
            })
            .collect();
        let out = &mut dst[dy * width..(dy + 1) * width];
        let bf: Vec<f32> = w
            .iter()
            .map(|&b| b as f32 * (1.0 / (COEF_SCALE * COEF_SCALE)))
            .collect();
        for (x, o) in out.iter_mut().enumerate() {
            if x < simd_end {
                let mut t = srows[3][x] as f32 * bf[3];
                for j in (0..3).rev() {
                    t += srows[j][x] as f32 * bf[j];
                }
                *o = t.round_ties_even().clamp(0.0, 255.0) as u8;
            } else {
                let mut v = 0i32;
                for j in 0..k {
                    v = v.wrapping_add(srows[j][x].wrapping_mul(w[j]));
                }
                let r = v.wrapping_add(1 << (2 * COEF_BITS - 1)) >> (2 * COEF_BITS);
                *o = r.clamp(0, 255) as u8;
            }
        }
    }
    dst
}

/// One source cell's share of one destination cell.
struct AreaTab {
    di: usize,
    si: usize,
    alpha: f32,
}

fn area_tab(src_len: usize, dst_len: usize, scale: f64) -> Vec<AreaTab> {
    let mut tab = Vec::new();
    for d in 0..dst_len {
        let fs1 = d as f64 * scale;
        let fs2 = fs1 + scale;
        let cell = scale.min(src_len as f64 - fs1);
        let mut s2 = fs2.floor() as isize;
        let mut s1 = fs1.ceil() as isize;
        s2 = s2.min(src_len as isize - 1);
        s1 = s1.min(s2);
        if s1 as f64 - fs1 > 1e-3 {
            tab.push(AreaTab {
                di: d,
                si: (s1 - 1).max(0) as usize,
                alpha: ((s1 as f64 - fs1) / cell) as f32,
            });
        }
        for s in s1..s2 {
            tab.push(AreaTab {
                di: d,
                si: s.max(0) as usize,
                alpha: (1.0 / cell) as f32,
            });
        }
        if fs2 - s2 as f64 > 1e-3 {
            tab.push(AreaTab {
                di: d,
                si: s2.max(0) as usize,
                alpha: ((fs2 - s2 as f64).min(1.0).min(cell) / cell) as f32,
            });
        }
    }
    tab
}

/// OpenCV's general INTER_AREA shrink: float weights of overlapping cells.
fn area_shrink<T: Copy, U: Default + Copy>(
    src: &[T],
    cn: usize,
    g: Geometry,
    load: impl Fn(T) -> f32,
    store: impl Fn(f32) -> U,
) -> Vec<U> {
    let xt = area_tab(g.sw, g.dw, 1.0 / g.inv_x);
    let yt = area_tab(g.sh, g.dh, 1.0 / g.inv_y);
    let width = g.dw * cn;
    let mut dst = vec![U::default(); g.dh * width];
    let mut buf = vec![0f32; width];
    let mut sum = vec![0f32; width];
    let Some(first) = yt.first() else {
        return dst;
    };
    let mut prev = first.di;
    for y in &yt {
        let s = &src[y.si * g.sw * cn..(y.si + 1) * g.sw * cn];
        buf.iter_mut().for_each(|b| *b = 0.0);
        for x in &xt {
            for c in 0..cn {
                buf[x.di * cn + c] += load(s[x.si * cn + c]) * x.alpha;
            }
        }
        if y.di != prev {
            let out = &mut dst[prev * width..(prev + 1) * width];
            for ((o, sm), b) in out.iter_mut().zip(sum.iter_mut()).zip(&buf) {
                *o = store(*sm);
                *sm = y.alpha * b;
            }
            prev = y.di;
        } else {
            for (sm, b) in sum.iter_mut().zip(&buf) {
                *sm += y.alpha * b;
            }
        }
    }
    let out = &mut dst[prev * width..(prev + 1) * width];
    for (o, sm) in out.iter_mut().zip(&sum) {
        *o = store(*sm);
    }
    dst
}

/// OpenCV's INTER_AREA for integer shrink factors on `u8`: block means,
/// `(sum + 2) >> 2` for 2x2 blocks, `round(sum * (1 / area))` otherwise.
fn area_fast_u8(src: &[u8], cn: usize, g: Geometry, ix: usize, iy: usize) -> Vec<u8> {
    let width = g.dw * cn;
    let mut dst = vec![0u8; g.dh * width];
    let scale = 1.0f32 / (ix * iy) as f32;
    let two = ix == 2 && iy == 2 && matches!(cn, 1 | 3 | 4);
    for dy in 0..g.dh {
        for dx in 0..g.dw {
            for c in 0..cn {
                let mut sum = 0i32;
                for sy in dy * iy..(dy * iy + iy).min(g.sh) {
                    for sx in dx * ix..(dx * ix + ix).min(g.sw) {
                        sum += src[(sy * g.sw + sx) * cn + c] as i32;
                    }
                }
                dst[dy * width + dx * cn + c] = if two {
                    ((sum + 2) >> 2) as u8
                } else {
                    (sum as f32 * scale).round_ties_even().clamp(0.0, 255.0) as u8
                };
            }
        }
    }
    dst
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn by_factor_rounds_size_and_keeps_factor() {
        let g = Geometry::by_factor(5, 3, 0.5);
        assert_eq!((g.dw, g.dh), (2, 2));
        assert_eq!(g.inv_x, 0.5);
    }

    #[test]
    fn constant_image_stays_constant() {
        let src = vec![7u8; 9 * 7 * 3];
        for interp in [Interp::Cubic, Interp::Lanczos4, Interp::Area] {
            let out = resize_u8(&src, 3, Geometry::to_size(9, 7, 4, 3), interp);
            assert!(out.iter().all(|&v| v == 7), "{interp:?}");
            let out = resize_u8(&src, 3, Geometry::to_size(9, 7, 20, 13), interp);
            assert!(out.iter().all(|&v| v == 7), "{interp:?}");
        }
    }

    #[test]
    fn empty_sizes_do_not_panic() {
        assert!(
            resize_f32(&[], 1, Geometry::to_size(0, 0, 3, 3), Interp::Cubic)
                .iter()
                .all(|&v| v == 0.0)
        );
        assert!(resize_u8(&[1, 2], 1, Geometry::to_size(2, 1, 0, 4), Interp::Area).is_empty());
    }
}
