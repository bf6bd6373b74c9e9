//! A minimal, bounds-checked FlatBuffers reader: just what the TFLite schema
//! needs (tables, scalars, strings, vectors of scalars and of tables).

use crate::TfliteError;

type R<T> = Result<T, TfliteError>;

fn short(what: &str) -> TfliteError {
    TfliteError::Malformed(format!("{what} points outside the file"))
}

/// The whole flatbuffer.
#[derive(Clone, Copy)]
pub(crate) struct Buf<'a>(pub &'a [u8]);

impl<'a> Buf<'a> {
    fn bytes<const N: usize>(&self, pos: usize) -> R<[u8; N]> {
        self.0
            .get(pos..pos.checked_add(N).ok_or_else(|| short("offset"))?)
            .and_then(|s| s.try_into().ok())
            .ok_or_else(|| short("field"))
    }
    pub fn u8(&self, pos: usize) -> R<u8> {
        Ok(self.bytes::<1>(pos)?[0])
    }
    pub fn u16(&self, pos: usize) -> R<u16> {
        Ok(u16::from_le_bytes(self.bytes(pos)?))
    }
    pub fn u32(&self, pos: usize) -> R<u32> {
        Ok(u32::from_le_bytes(self.bytes(pos)?))
    }
    pub fn i32(&self, pos: usize) -> R<i32> {
        Ok(i32::from_le_bytes(self.bytes(pos)?))
    }
    pub fn u64(&self, pos: usize) -> R<u64> {
        Ok(u64::from_le_bytes(self.bytes(pos)?))
    }

    /// Follows a `uoffset` stored at `pos`.
    fn follow(&self, pos: usize) -> R<usize> {
        pos.checked_add(self.u32(pos)? as usize)
            .filter(|p| *p < self.0.len())
            .ok_or_else(|| short("offset"))
    }

    /// The root table.
    pub fn root(&self) -> R<Table<'a>> {
        Table::at(*self, self.follow(0)?)
    }
}

/// A table: a position and its vtable.
#[derive(Clone, Copy)]
pub(crate) struct Table<'a> {
    buf: Buf<'a>,
    pos: usize,
    vtable: usize,
    vlen: usize,
}

impl<'a> Table<'a> {
    fn at(buf: Buf<'a>, pos: usize) -> R<Self> {
        let soff = buf.i32(pos)? as i64;
        let vtable = usize::try_from(pos as i64 - soff).map_err(|_| short("vtable"))?;
        let vlen = buf.u16(vtable)? as usize;
        Ok(Self {
            buf,
            pos,
            vtable,
            vlen,
        })
    }

    /// Absolute position of field `id`, if present.
    fn field(&self, id: usize) -> R<Option<usize>> {
        let slot = 4 + 2 * id;
        if slot + 2 > self.vlen {
            return Ok(None);
        }
        let off = self.buf.u16(self.vtable + slot)? as usize;
        Ok((off != 0).then_some(self.pos + off))
    }

    pub fn u8_or(&self, id: usize, default: u8) -> R<u8> {
        self.field(id)?.map_or(Ok(default), |p| self.buf.u8(p))
    }
    pub fn i32_or(&self, id: usize, default: i32) -> R<i32> {
        self.field(id)?.map_or(Ok(default), |p| self.buf.i32(p))
    }
    pub fn u32_or(&self, id: usize, default: u32) -> R<u32> {
        self.field(id)?.map_or(Ok(default), |p| self.buf.u32(p))
    }
    pub fn u64_or(&self, id: usize, default: u64) -> R<u64> {
        self.field(id)?.map_or(Ok(default), |p| self.buf.u64(p))
    }
    pub fn bool_or(&self, id: usize, default: bool) -> R<bool> {
        Ok(self.u8_or(id, default as u8)? != 0)
    }

    pub fn table(&self, id: usize) -> R<Option<Table<'a>>> {
        match self.field(id)? {
            Some(p) => Ok(Some(Table::at(self.buf, self.buf.follow(p)?)?)),
            None => Ok(None),
        }
    }

    /// (start, length) of the vector in field `id` with `elem`-byte elements.
    fn vector(&self, id: usize, elem: usize) -> R<Option<(usize, usize)>> {
        let Some(p) = self.field(id)? else {
            return Ok(None);
        };
        let start = self.buf.follow(p)?;
        let len = self.buf.u32(start)? as usize;
        let end = len
            .checked_mul(elem)
            .and_then(|b| b.checked_add(start + 4))
            .ok_or_else(|| short("vector"))?;
        if end > self.buf.0.len() {
            return Err(short("vector"));
        }
        Ok(Some((start + 4, len)))
    }

    pub fn bytes(&self, id: usize) -> R<Option<&'a [u8]>> {
        Ok(self.vector(id, 1)?.map(|(s, n)| &self.buf.0[s..s + n]))
    }

    pub fn string(&self, id: usize) -> R<String> {
        Ok(self
            .bytes(id)?
            .map(|b| String::from_utf8_lossy(b).into_owned())
            .unwrap_or_default())
    }

    pub fn i32s(&self, id: usize) -> R<Vec<i32>> {
        let Some((s, n)) = self.vector(id, 4)? else {
            return Ok(Vec::new());
        };
        (0..n).map(|i| self.buf.i32(s + 4 * i)).collect()
    }

    pub fn u16s(&self, id: usize) -> R<Vec<u16>> {
        let Some((s, n)) = self.vector(id, 2)? else {
            return Ok(Vec::new());
        };
        (0..n).map(|i| self.buf.u16(s + 2 * i)).collect()
    }

    pub fn tables(&self, id: usize) -> R<Vec<Table<'a>>> {
        let Some((s, n)) = self.vector(id, 4)? else {
            return Ok(Vec::new());
        };
        (0..n)
            .map(|i| Table::at(self.buf, self.buf.follow(s + 4 * i)?))
            .collect()
    }
}
