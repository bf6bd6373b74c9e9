//! Encoding of the parameter section: groups of typed, dimensioned parameters, each record
//! pointing at the next. Which parameters we write is decided in `groups.rs`.

use crate::BLOCK;
use crate::error::C3dError;
use crate::header::C3D_KEY;

/// Processor type of the parameter section's 4th byte: Intel, i.e. IEEE little-endian.
pub(crate) const PROCESSOR_INTEL: u8 = 84;
/// The parameter-section header's block count is one byte.
const MAX_BLOCKS: usize = 255;

/// A parameter's values, with the C3D type code they are stored as.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Data {
    /// Type -1: bytes, space-padded strings for text.
    Char(Vec<u8>),
    /// Type 2: 16-bit signed integers.
    Int16(Vec<i16>),
    /// Type 4: float32.
    Float(Vec<f32>),
}

impl Data {
    fn type_code(&self) -> i8 {
        match self {
            Data::Char(_) => -1,
            Data::Int16(_) => 2,
            Data::Float(_) => 4,
        }
    }

    fn bytes(&self) -> Vec<u8> {
        match self {
            Data::Char(v) => v.clone(),
            Data::Int16(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            Data::Float(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        }
    }
}

/// One parameter: name (upper case), description, dimensions (first varies fastest) and data.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Parameter {
    pub name: &'static str,
    pub description: &'static str,
    pub dims: Vec<u8>,
    pub data: Data,
}

impl Parameter {
    /// A single integer, written with no dimensions as Vicon writes scalars.
    pub(crate) fn int(name: &'static str, description: &'static str, v: i16) -> Self {
        Self {
            name,
            description,
            dims: vec![],
            data: Data::Int16(vec![v]),
        }
    }

    /// A single float, written with no dimensions.
    pub(crate) fn float(name: &'static str, description: &'static str, v: f32) -> Self {
        Self {
            name,
            description,
            dims: vec![],
            data: Data::Float(vec![v]),
        }
    }

    /// A 1-D integer array.
    pub(crate) fn ints(
        name: &'static str,
        description: &'static str,
        v: Vec<i16>,
    ) -> Result<Self, C3dError> {
        Ok(Self {
            name,
            description,
            dims: vec![dim(name, v.len())?],
            data: Data::Int16(v),
        })
    }

    /// A float array of the given dimensions (first varies fastest); `v` must fill them.
    pub(crate) fn floats(
        name: &'static str,
        description: &'static str,
        dims: &[usize],
        v: Vec<f32>,
    ) -> Result<Self, C3dError> {
        let dims = dims
            .iter()
            .map(|&d| dim(name, d))
            .collect::<Result<Vec<_>, _>>()?;
        let count: usize = dims.iter().map(|&d| usize::from(d)).product();
        if count != v.len() {
            // Only our own code builds these; refuse rather than write a corrupt record.
            return Err(C3dError::DimensionTooLarge {
                name: name.to_string(),
                len: v.len(),
            });
        }
        Ok(Self {
            name,
            description,
            dims,
            data: Data::Float(v),
        })
    }

    /// One string: a 1-D char array of its length.
    pub(crate) fn text(
        name: &'static str,
        description: &'static str,
        s: &str,
    ) -> Result<Self, C3dError> {
        let bytes = s.as_bytes().to_vec();
        Ok(Self {
            name,
            description,
            dims: vec![dim(name, bytes.len())?],
            data: Data::Char(bytes),
        })
    }

    /// Several strings: a 2-D char array [longest length, count], each padded with spaces
    /// (readers trim them). The width is at least 1 so that no dimension is 0.
    pub(crate) fn texts(
        name: &'static str,
        description: &'static str,
        strings: &[&str],
    ) -> Result<Self, C3dError> {
        let width = strings.iter().map(|s| s.len()).max().unwrap_or(0).max(1);
        let mut bytes = Vec::with_capacity(width * strings.len());
        for s in strings {
            bytes.extend_from_slice(s.as_bytes());
            bytes.resize(bytes.len() + width - s.len(), b' ');
        }
        let dims = vec![dim(name, width)?, dim(name, strings.len())?];
        Ok(Self {
            name,
            description,
            dims,
            data: Data::Char(bytes),
        })
    }
}

/// A group of parameters; its id in the file is its position + 1.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Group {
    pub name: &'static str,
    pub description: &'static str,
    pub parameters: Vec<Parameter>,
}

/// The whole parameter section, padded to whole blocks: 4-byte section header, every group
/// record followed by its parameters' records, then a terminating record of name length 0.
pub(crate) fn encode_section(groups: &[Group]) -> Result<Vec<u8>, C3dError> {
    // Byte 0 = 1: the first record starts right after this 4-byte header (readers such as
    // ezc3d use it as an offset). Byte 2 (block count) is filled in at the end.
    let mut out = vec![1, C3D_KEY, 0, PROCESSOR_INTEL];
    for (index, group) in groups.iter().enumerate() {
        let id = i8::try_from(index + 1).map_err(|_| C3dError::DimensionTooLarge {
            name: group.name.to_string(),
            len: index + 1,
        })?;
        // Group record: ..., offset, description length, description.
        let mut tail = Vec::new();
        push_short_text(&mut tail, group.name, group.description)?;
        record(&mut out, group.name, -id, &tail)?;
        for p in &group.parameters {
            let mut tail = vec![p.data.type_code() as u8, p.dims.len() as u8];
            tail.extend_from_slice(&p.dims);
            tail.extend_from_slice(&p.data.bytes());
            push_short_text(&mut tail, p.name, p.description)?;
            record(&mut out, p.name, id, &tail)?;
        }
    }
    // Terminator: name length 0 (and id 0). Both ezc3d and BTK stop reading here.
    out.extend_from_slice(&[0, 0]);
    let blocks = out.len().div_ceil(BLOCK);
    if blocks > MAX_BLOCKS {
        return Err(C3dError::ParametersTooLarge(blocks));
    }
    out.resize(blocks * BLOCK, 0);
    out[2] = blocks as u8;
    Ok(out)
}

/// Appends one record: name length, id (negative for groups), name, then the 16-bit offset from
/// the offset field itself to the next record, then `tail`.
fn record(out: &mut Vec<u8>, name: &str, id: i8, tail: &[u8]) -> Result<(), C3dError> {
    let len = i8::try_from(name.len())
        .ok()
        .filter(|&l| l > 0)
        .ok_or_else(|| C3dError::DimensionTooLarge {
            name: name.to_string(),
            len: name.len(),
        })?;
    let offset = u16::try_from(tail.len() + 2).map_err(|_| C3dError::DimensionTooLarge {
        name: name.to_string(),
        len: tail.len(),
    })?;
    out.push(len as u8);
    out.push(id as u8);
    out.extend_from_slice(name.as_bytes());
    out.extend_from_slice(&offset.to_le_bytes());
    out.extend_from_slice(tail);
    Ok(())
}

/// Appends a description: its length as one byte, then its bytes.
fn push_short_text(out: &mut Vec<u8>, owner: &str, text: &str) -> Result<(), C3dError> {
    out.push(dim(owner, text.len())?);
    out.extend_from_slice(text.as_bytes());
    Ok(())
}

/// A dimension (or description length), which C3D stores in one byte.
fn dim(name: &str, len: usize) -> Result<u8, C3dError> {
    u8::try_from(len).map_err(|_| C3dError::DimensionTooLarge {
        name: name.to_string(),
        len,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scalar_int_record() {
        let g = Group {
            name: "POINT",
            description: "",
            parameters: vec![Parameter::int("USED", "", 3)],
        };
        let s = encode_section(&[g]).unwrap();
        assert_eq!(s.len(), 512);
        assert_eq!(&s[..4], &[1, 0x50, 1, 84]);
        // Group: len 5, id -1, "POINT", offset 3 (2 + description length byte), desc len 0.
        assert_eq!(&s[4..14], &[5, 0xff, b'P', b'O', b'I', b'N', b'T', 3, 0, 0]);
        // Parameter: len 4, id 1, "USED", offset 7 = 2 + type + ndims + 2 data + desc len.
        assert_eq!(
            &s[14..27],
            &[4, 1, b'U', b'S', b'E', b'D', 7, 0, 2, 0, 3, 0, 0]
        );
        // Then the terminator and zero padding.
        assert!(s[27..].iter().all(|&b| b == 0));
    }

    #[test]
    fn text_arrays_pad_with_spaces() {
        let p = Parameter::texts("LABELS", "", &["Hip", "Knee", ""]).unwrap();
        assert_eq!(p.dims, vec![4, 3]);
        assert_eq!(p.data, Data::Char(b"Hip Knee    ".to_vec()));
        let empty = Parameter::texts("X", "", &[]).unwrap();
        assert_eq!(empty.dims, vec![1, 0]);
        let one = Parameter::text("UNITS", "", "mm").unwrap();
        assert_eq!((one.dims, one.data), (vec![2], Data::Char(b"mm".to_vec())));
    }

    #[test]
    fn float_array_record_with_description() {
        let p = Parameter::floats("TIMES", "ab", &[2, 2], vec![0.0, 1.5, 1.0, 2.25]).unwrap();
        let g = Group {
            name: "EVENT",
            description: "",
            parameters: vec![p],
        };
        let s = encode_section(&[g]).unwrap();
        let at = 4 + 2 + 5 + 2 + 1; // after the group record
        assert_eq!(&s[at..at + 7], &[5, 1, b'T', b'I', b'M', b'E', b'S']);
        // offset = 2 + type + ndims + 2 dims + 16 data + 1 + 2 description
        assert_eq!(
            &s[at + 7..at + 9],
            &(2u16 + 1 + 1 + 2 + 16 + 1 + 2).to_le_bytes()
        );
        assert_eq!(&s[at + 9..at + 13], &[4, 2, 2, 2]);
        assert_eq!(&s[at + 13..at + 17], &0.0f32.to_le_bytes());
        assert_eq!(&s[at + 17..at + 21], &1.5f32.to_le_bytes());
        assert_eq!(&s[at + 29..at + 32], &[2, b'a', b'b']);
        assert!(Parameter::floats("T", "", &[2, 2], vec![0.0]).is_err());
    }

    #[test]
    fn group_ids_and_block_count() {
        let groups: Vec<Group> = ["A", "B"]
            .iter()
            .map(|&name| Group {
                name,
                description: "",
                parameters: vec![Parameter::int("N", "", 1)],
            })
            .collect();
        let s = encode_section(&groups).unwrap();
        // Second group's record: id -2; its parameter: id 2.
        let second = 4 + (2 + 1 + 2 + 1) + (2 + 1 + 2 + 1 + 1 + 2 + 1);
        assert_eq!(&s[second..second + 3], &[1, 0xfe, b'A' + 1]);
        assert_eq!(s[second + 6 + 1], 2);

        // A section over one block reports its block count.
        let long: Vec<String> = (0..200).map(|i| format!("MARKER_{i:03}")).collect();
        let refs: Vec<&str> = long.iter().map(String::as_str).collect();
        let g = Group {
            name: "POINT",
            description: "",
            parameters: vec![Parameter::texts("LABELS", "", &refs).unwrap()],
        };
        let s = encode_section(&[g]).unwrap();
        assert_eq!(s.len() % 512, 0);
        assert_eq!(usize::from(s[2]), s.len() / 512);
        assert!(s[2] >= 4);
    }

    #[test]
    fn oversized_dimensions_are_errors() {
        let many = vec![0i16; 256];
        assert!(matches!(
            Parameter::ints("X", "", many),
            Err(C3dError::DimensionTooLarge { .. })
        ));
        let long = "x".repeat(256);
        assert!(Parameter::text("X", "", &long).is_err());
    }
}
