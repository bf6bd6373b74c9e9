//! The header: the file's first 512-byte block, which points at the parameter and data sections
//! and repeats the point count, frame range, scale and rate for readers that stop there.

use crate::BLOCK;

/// Block number (1-based, as C3D counts) where the parameter section starts: right after the header.
pub(crate) const PARAMETER_BLOCK: u8 = 2;
/// Second byte of the file and of the parameter section: identifies a C3D file.
pub(crate) const C3D_KEY: u8 = 0x50;
/// Word 150 holds this when event labels in the header are 4 characters long (the modern form).
const FOUR_CHAR_EVENT_LABELS: u16 = 12345;

/// The values the header repeats from the parameters.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Header {
    pub points: u16,
    pub first_frame: u16,
    pub last_frame: u16,
    /// Negative: the data are stored as float32 (POINT:SCALE, same value).
    pub scale: f32,
    /// 1-based block number of the first data block (POINT:DATA_START).
    pub data_start_block: u16,
    pub rate_hz: f32,
}

impl Header {
    /// The 512 header bytes, Intel byte order. Word n (1-based) sits at byte 2 * (n - 1).
    pub(crate) fn encode(&self) -> [u8; BLOCK] {
        let mut b = [0u8; BLOCK];
        b[0] = PARAMETER_BLOCK;
        b[1] = C3D_KEY;
        put_u16(&mut b, 2, self.points);
        // Word 3: analog samples per frame, all channels together; we write no analog data.
        put_u16(&mut b, 3, 0);
        put_u16(&mut b, 4, self.first_frame);
        put_u16(&mut b, 5, self.last_frame);
        // Word 6: maximum interpolation gap; we interpolate nothing.
        put_u16(&mut b, 6, 0);
        b[12..16].copy_from_slice(&self.scale.to_le_bytes()); // words 7-8
        put_u16(&mut b, 9, self.data_start_block);
        // Word 10: analog samples per point frame. 1 (not 0) keeps ANALOG:RATE / POINT:RATE
        // consistent for readers that divide by it, although there are no channels.
        put_u16(&mut b, 10, 1);
        b[20..24].copy_from_slice(&self.rate_hz.to_le_bytes()); // words 11-12
        // Words 148-149 (label and range section) stay 0: there is none.
        put_u16(&mut b, 150, FOUR_CHAR_EVENT_LABELS);
        // Word 151: number of header events, left at 0 on purpose. The events live in the EVENT
        // group; BTK (Mokka) loads header events *and* EVENT events, so writing both would show
        // every event twice there.
        put_u16(&mut b, 151, 0);
        b
    }
}

/// Stores `v` as 16-bit word `word` (1-based, as the C3D documentation numbers them).
fn put_u16(b: &mut [u8; BLOCK], word: usize, v: u16) {
    let at = 2 * (word - 1);
    b[at..at + 2].copy_from_slice(&v.to_le_bytes());
}

#[cfg(test)]
mod tests {
    use super::*;

    fn word(b: &[u8], n: usize) -> u16 {
        u16::from_le_bytes([b[2 * (n - 1)], b[2 * (n - 1) + 1]])
    }

    #[test]
    fn header_bytes() {
        let h = Header {
            points: 25,
            first_frame: 11,
            last_frame: 310,
            scale: -1.0,
            data_start_block: 5,
            rate_hz: 29.97,
        };
        let b = h.encode();
        assert_eq!(&b[..2], &[2, 0x50]);
        assert_eq!(word(&b, 2), 25);
        assert_eq!(word(&b, 3), 0);
        assert_eq!(word(&b, 4), 11);
        assert_eq!(word(&b, 5), 310);
        assert_eq!(&b[12..16], &(-1.0f32).to_le_bytes());
        assert_eq!(&b[12..16], &[0, 0, 0x80, 0xbf]);
        assert_eq!(word(&b, 9), 5);
        assert_eq!(word(&b, 10), 1);
        assert_eq!(f32::from_le_bytes([b[20], b[21], b[22], b[23]]), 29.97f32);
        assert_eq!(word(&b, 150), 12345);
        assert_eq!(&b[298..300], &[0x39, 0x30]);
        assert_eq!(word(&b, 151), 0);
        // Everything else is zero.
        let set: Vec<usize> = (0..BLOCK).filter(|&i| b[i] != 0).collect();
        assert!(
            set.iter().all(|&i| i < 24 || (298..300).contains(&i)),
            "{set:?}"
        );
    }
}
