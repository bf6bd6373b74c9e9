//! The ONNX protobuf messages `to_onnx` needs, encoded by hand (field numbers from onnx.proto).

/// Protobuf writer: fields are appended as (tag, payload).
#[derive(Default)]
pub(super) struct Pb(pub(super) Vec<u8>);

impl Pb {
    fn varint(&mut self, mut v: u64) {
        while v >= 0x80 {
            self.0.push((v as u8) | 0x80);
            v >>= 7;
        }
        self.0.push(v as u8);
    }
    pub(super) fn int(&mut self, field: u32, v: i64) -> &mut Self {
        self.varint((field as u64) << 3);
        self.varint(v as u64);
        self
    }
    pub(super) fn bytes(&mut self, field: u32, b: &[u8]) -> &mut Self {
        self.varint(((field as u64) << 3) | 2);
        self.varint(b.len() as u64);
        self.0.extend_from_slice(b);
        self
    }
    pub(super) fn str(&mut self, field: u32, s: &str) -> &mut Self {
        self.bytes(field, s.as_bytes())
    }
    pub(super) fn msg(&mut self, field: u32, m: Pb) -> &mut Self {
        self.bytes(field, &m.0)
    }
}

/// A node attribute's value.
pub(super) enum Attr {
    Int(i64),
    Ints(Vec<i64>),
    Str(&'static str),
}

/// An `AttributeProto`.
pub(super) fn attr(name: &str, a: Attr) -> Pb {
    let mut p = Pb::default();
    p.str(1, name);
    match a {
        Attr::Int(i) => p.int(3, i).int(20, 2),
        Attr::Str(s) => p.bytes(4, s.as_bytes()).int(20, 3),
        Attr::Ints(v) => {
            for i in v {
                p.int(8, i);
            }
            p.int(20, 7)
        }
    };
    p
}

fn tensor(name: &str, dims: &[usize], data_type: i64, raw: &[u8]) -> Pb {
    let mut p = Pb::default();
    for &d in dims {
        p.int(1, d as i64);
    }
    p.int(2, data_type).str(8, name).bytes(9, raw);
    p
}

/// A float `TensorProto` (little-endian raw data).
pub(super) fn f32_tensor(name: &str, dims: &[usize], v: &[f32]) -> Pb {
    let mut raw = Vec::with_capacity(4 * v.len());
    for x in v {
        raw.extend_from_slice(&x.to_le_bytes());
    }
    tensor(name, dims, 1, &raw)
}

/// A 1-D int64 `TensorProto`.
pub(super) fn i64_tensor(name: &str, v: &[i64]) -> Pb {
    let mut raw = Vec::with_capacity(8 * v.len());
    for x in v {
        raw.extend_from_slice(&x.to_le_bytes());
    }
    tensor(name, &[v.len()], 7, &raw)
}

/// A float `ValueInfoProto` of a fixed shape.
pub(super) fn value_info(name: &str, dims: &[usize]) -> Pb {
    let mut shape = Pb::default();
    for &d in dims {
        let mut dim = Pb::default();
        dim.int(1, d as i64);
        shape.msg(1, dim);
    }
    let mut tt = Pb::default();
    tt.int(1, 1).msg(2, shape);
    let mut ty = Pb::default();
    ty.msg(1, tt);
    let mut p = Pb::default();
    p.str(1, name).msg(2, ty);
    p
}
