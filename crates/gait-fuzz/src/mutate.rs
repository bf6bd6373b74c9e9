//! The mutator: what a truncated, hand-edited or foreign file looks like, made from a real one.
//! Byte flips and interesting bytes, truncation, deletion and duplication of spans, splices with
//! another seed, and numbers in text replaced by extreme ones (huge, negative, NaN, inf).

/// xorshift64*: small, fast and reproducible from a seed (a run is repeatable from its seed).
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed.max(1))
    }

    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// Uniform in `0..n` (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
}

const INTERESTING: [u8; 10] = [0, 1, 0x7f, 0x80, 0xff, b'\n', b',', b'"', b'[', b'{'];

/// Text that parsers of numbers and sizes must survive.
const NUMBERS: [&str; 14] = [
    "NaN",
    "inf",
    "-inf",
    "-1",
    "0",
    "1e308",
    "-1e308",
    "1e-320",
    "18446744073709551615",
    "99999999999999999999999",
    "4294967296",
    "2147483648",
    "1000000000000",
    "",
];

/// One mutation of `data` (which may be empty); `other` is another seed to splice from.
pub fn mutate(rng: &mut Rng, data: &mut Vec<u8>, other: &[u8]) {
    let len = data.len();
    match rng.below(9) {
        0 if len > 0 => {
            let i = rng.below(len);
            data[i] ^= 1 << rng.below(8);
        }
        1 if len > 0 => {
            let i = rng.below(len);
            data[i] = INTERESTING[rng.below(INTERESTING.len())];
        }
        2 if len > 0 => data.truncate(rng.below(len)),
        3 if len > 1 => {
            let a = rng.below(len);
            let b = (a + 1 + rng.below(64.min(len - a))).min(len);
            data.drain(a..b);
        }
        4 if len > 0 => {
            let a = rng.below(len);
            let b = (a + 1 + rng.below(256.min(len - a))).min(len);
            let chunk = data[a..b].to_vec();
            let at = rng.below(len + 1);
            data.splice(at..at, chunk);
        }
        5 if !other.is_empty() => {
            // Splice: a prefix of this seed with a suffix of another.
            let cut = rng.below(len + 1);
            let from = rng.below(other.len());
            data.truncate(cut);
            data.extend_from_slice(&other[from..]);
        }
        6 => replace_number(rng, data),
        7 if len > 0 => {
            // Four bytes of a size field: 0, -1 or a huge count.
            let i = rng.below(len);
            let v: u32 = [0, u32::MAX, 0x7fff_ffff, 1 << 30][rng.below(4)];
            for (k, b) in v.to_le_bytes().iter().enumerate() {
                if let Some(slot) = data.get_mut(i + k) {
                    *slot = *b;
                }
            }
        }
        _ => {
            let at = rng.below(len + 1);
            data.insert(at, INTERESTING[rng.below(INTERESTING.len())]);
        }
    }
}

/// Replaces a run of digits (a number in text) with one of [`NUMBERS`].
fn replace_number(rng: &mut Rng, data: &mut Vec<u8>) {
    let len = data.len();
    if len == 0 {
        return;
    }
    let start = rng.below(len);
    let Some(a) = (start..len).find(|&i| data[i].is_ascii_digit()) else {
        return;
    };
    let b = (a..len)
        .find(|&i| !(data[i].is_ascii_digit() || data[i] == b'.'))
        .unwrap_or(len);
    let with = NUMBERS[rng.below(NUMBERS.len())].as_bytes();
    data.splice(a..b, with.iter().copied());
}

/// `seed` mutated 1 to 8 times.
pub fn variant(rng: &mut Rng, seed: &[u8], other: &[u8]) -> Vec<u8> {
    let mut data = seed.to_vec();
    for _ in 0..1 + rng.below(8) {
        mutate(rng, &mut data, other);
    }
    data
}

/// `seed` with 1 to 3 of its numbers replaced by extreme ones, the structure left intact: the
/// inputs that reach past the parser into the analysis.
pub fn numbers_only(rng: &mut Rng, seed: &[u8]) -> Vec<u8> {
    let mut data = seed.to_vec();
    for _ in 0..1 + rng.below(3) {
        replace_number(rng, &mut data);
    }
    data
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_same_seed_gives_the_same_inputs() {
        let seed = b"frame,x,y\n12,812.5,901.0\n".to_vec();
        let run = |s| {
            let mut rng = Rng::new(s);
            (0..50)
                .map(|_| variant(&mut rng, &seed, b"other"))
                .collect::<Vec<_>>()
        };
        assert_eq!(run(7), run(7));
        assert_ne!(run(7), run(8));
        // Mutations do change the input (most of the time).
        assert!(run(7).iter().filter(|v| **v != seed).count() > 40);
    }

    #[test]
    fn numbers_in_text_are_replaced_whole() {
        let mut rng = Rng::new(3);
        let mut seen = std::collections::BTreeSet::new();
        for _ in 0..200 {
            let mut d = b"x = 812.5\n".to_vec();
            replace_number(&mut rng, &mut d);
            seen.insert(String::from_utf8(d).unwrap());
        }
        assert!(
            seen.contains("x = NaN\n") && seen.contains("x = 1e308\n"),
            "{seen:?}"
        );
    }
}
