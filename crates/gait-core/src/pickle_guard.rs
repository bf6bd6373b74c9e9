//! Declared lengths of a pickle stream, checked before an unpickler allocates them.
//!
//! PyTorch checkpoints (`.pth`) are pickles. candle's unpickler allocates a `BINUNICODE`
//! string of the length the file declares (up to 4 GiB) before reading it, so a truncated or
//! hostile file could make it ask for gigabytes. [`check`] walks one pickle's opcodes (those
//! candle reads) and refuses a length that runs past the end of the data.

/// Checks the pickle at the start of `data` up to its STOP opcode; returns its length in
/// bytes. An opcode candle does not read ends the walk without an error: candle refuses it
/// itself, before allocating anything.
pub fn check(data: &[u8]) -> Result<usize, String> {
    let mut i = 0usize;
    let need = |i: usize, n: usize, what: &str| -> Result<usize, String> {
        let end = i.checked_add(n).filter(|&e| e <= data.len());
        end.ok_or_else(|| {
            format!(
                "the pickle's {what} at byte {i} declares {n} bytes but only {} remain (truncated or corrupt file)",
                data.len().saturating_sub(i)
            )
        })
    };
    while i < data.len() {
        let op = data[i];
        i += 1;
        i = match op {
            b'.' => return Ok(i),
            // PROTO, BINPUT, BINGET, BININT1
            0x80 | b'q' | b'h' | b'K' => need(i, 1, "argument")?,
            // BININT2
            b'M' => need(i, 2, "argument")?,
            // LONG_BINPUT, LONG_BINGET, BININT
            b'r' | b'j' | b'J' => need(i, 4, "argument")?,
            // BINFLOAT
            b'G' => need(i, 8, "argument")?,
            // LONG1: a length byte, then that many bytes (candle reads at most 8).
            0x8a => {
                let at = need(i, 1, "length")?;
                if data[i] > 8 {
                    return Err(format!(
                        "the pickle's integer at byte {i} has {} bytes; a checkpoint's have at most 8",
                        data[i]
                    ));
                }
                need(at, data[i] as usize, "integer")?
            }
            // BINUNICODE: a 4-byte length, then the string.
            b'X' => {
                let at = need(i, 4, "length")?;
                let len = u32::from_le_bytes([data[i], data[i + 1], data[i + 2], data[i + 3]]);
                need(at, len as usize, "string")?
            }
            // GLOBAL: module and name, each a line.
            b'c' => {
                let mut at = i;
                for _ in 0..2 {
                    let nl = data[at..].iter().position(|&b| b == b'\n').ok_or_else(|| {
                        format!("the pickle's GLOBAL at byte {i} has no end of line")
                    })?;
                    at += nl + 1;
                }
                at
            }
            b')' | b'R' | b'(' | b't' | b'Q' | 0x85 | 0x86 | 0x87 | 0x88 | 0x89 | b'N' | b's'
            | b'u' | b'}' | b'd' | b'b' | 0x81 | b']' | b'a' | b'e' => i,
            _ => return Ok(i),
        };
    }
    Err("the pickle ends without its STOP opcode (truncated file)".into())
}

#[cfg(test)]
mod tests {
    use super::check;

    #[test]
    fn a_string_longer_than_the_data_is_refused() {
        // PROTO 2, BINUNICODE of 3 bytes "abc", STOP.
        let ok = [0x80, 2, b'X', 3, 0, 0, 0, b'a', b'b', b'c', b'.'];
        assert_eq!(check(&ok), Ok(ok.len()));
        let mut huge = ok;
        huge[3..7].copy_from_slice(&u32::MAX.to_le_bytes());
        let e = check(&huge).unwrap_err();
        assert!(e.contains("declares 4294967295 bytes"), "{e}");
        assert!(check(&ok[..6]).is_err());
        assert!(check(&ok[..10]).unwrap_err().contains("STOP"));
    }

    #[test]
    fn globals_and_longs_are_walked() {
        let mut p = vec![0x80, 2, b'c'];
        p.extend_from_slice(b"torch._utils\n_rebuild_tensor_v2\n");
        p.extend_from_slice(&[0x8a, 2, 0xff, 0x7f, b'.', 0xde, 0xad]);
        assert_eq!(check(&p), Ok(p.len() - 2));
        assert!(check(&[0x8a, 9, 1]).is_err());
        assert!(check(&[0x8a, 3, 1]).is_err());
    }
}
