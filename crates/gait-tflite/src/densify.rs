//! TFLite's sparse tensor format (`SparsityParameters`) back to dense order.

use crate::TfliteError;

/// Storage of one dimension, in traversal order.
#[derive(Debug, Clone, PartialEq)]
pub enum DimMeta {
    Dense(usize),
    /// Compressed sparse row: `segments[i]..segments[i+1]` index `indices`
    /// for the i-th position of the enclosing levels.
    SparseCsr {
        segments: Vec<usize>,
        indices: Vec<usize>,
    },
}

/// Sparsity parameters of a tensor.
#[derive(Debug, Clone, PartialEq)]
pub struct Sparsity {
    /// Order of the (n + k) dimensions: n tensor dims, then k block dims.
    pub traversal_order: Vec<usize>,
    /// For each block dim, the tensor dim it subdivides.
    pub block_map: Vec<usize>,
    pub dim_metadata: Vec<DimMeta>,
}

/// The largest dense tensor a sparse one may expand to (BlazePose's are under 10 MB).
pub const MAX_DENSE_BYTES: usize = 256 << 20;

impl Sparsity {
    /// Scatters `values` (stored elements in traversal order) into a dense
    /// row-major tensor of `shape`; each element is `elem` bytes wide.
    pub fn densify(
        &self,
        shape: &[usize],
        values: &[u8],
        elem: usize,
    ) -> Result<Vec<u8>, TfliteError> {
        let n = shape.len();
        let k = self.block_map.len();
        let bad = |m: &str| TfliteError::Malformed(format!("sparse tensor: {m}"));
        if self.traversal_order.len() != n + k || self.dim_metadata.len() != n + k {
            return Err(bad("traversal order / dim metadata length"));
        }
        if self.traversal_order.iter().any(|&d| d >= n + k)
            || self.block_map.iter().any(|&d| d >= n)
        {
            return Err(bad("dimension index out of range"));
        }
        // Block sizes are the dense sizes of the block dims' levels.
        let mut block_size = vec![1usize; k];
        for (level, &dim) in self.traversal_order.iter().enumerate() {
            if dim >= n {
                match self.dim_metadata[level] {
                    DimMeta::Dense(s) => block_size[dim - n] = s,
                    DimMeta::SparseCsr { .. } => return Err(bad("sparse block dimension")),
                }
            }
        }
        // The dense size is declared by the file: refused past the limit before allocating it.
        let bytes = shape
            .iter()
            .try_fold(elem, |a, &d| a.checked_mul(d))
            .filter(|&b| b <= MAX_DENSE_BYTES)
            .ok_or_else(|| bad("dense size (shape times element size) over the 256 MiB limit"))?;
        let mut state = State {
            sp: self,
            shape,
            block_size,
            elem,
            values,
            next: 0,
            idx: vec![0; n + k],
            out: vec![0u8; bytes],
        };
        state.populate(0, 0)?;
        Ok(state.out)
    }
}

struct State<'a> {
    sp: &'a Sparsity,
    shape: &'a [usize],
    block_size: Vec<usize>,
    elem: usize,
    values: &'a [u8],
    next: usize,
    idx: Vec<usize>,
    out: Vec<u8>,
}

impl State<'_> {
    fn populate(&mut self, level: usize, prev: usize) -> Result<(), TfliteError> {
        let bad = |m: &str| TfliteError::Malformed(format!("sparse tensor: {m}"));
        let n = self.shape.len();
        if level == self.sp.traversal_order.len() {
            // Called once per stored value: no allocation here.
            let mut lin = 0usize;
            for i in 0..n {
                let mut o = Some(self.idx[i]);
                for (j, &d) in self.sp.block_map.iter().enumerate() {
                    if d == i {
                        o = o.and_then(|o| {
                            o.checked_mul(self.block_size[j])?
                                .checked_add(self.idx[n + j])
                        });
                    }
                }
                match o {
                    Some(o) if o < self.shape[i] => lin = lin * self.shape[i] + o,
                    _ => return Err(bad("index outside the dense shape")),
                }
            }
            let src = self
                .values
                .get(self.next * self.elem..(self.next + 1) * self.elem)
                .ok_or_else(|| bad("fewer stored values than indices"))?;
            self.out[lin * self.elem..(lin + 1) * self.elem].copy_from_slice(src);
            self.next += 1;
            return Ok(());
        }
        let dim = self.sp.traversal_order[level];
        match &self.sp.dim_metadata[level] {
            DimMeta::Dense(size) => {
                for i in 0..*size {
                    self.idx[dim] = i;
                    self.populate(level + 1, prev * size + i)?;
                }
            }
            DimMeta::SparseCsr { segments, indices } => {
                let (a, b) = match (segments.get(prev), segments.get(prev + 1)) {
                    (Some(&a), Some(&b)) if a <= b && b <= indices.len() => (a, b),
                    _ => return Err(bad("CSR segments out of range")),
                };
                for (i, &ix) in indices.iter().enumerate().take(b).skip(a) {
                    self.idx[dim] = ix;
                    self.populate(level + 1, i)?;
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f32s(v: &[f32]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_le_bytes()).collect()
    }

    #[test]
    fn csr_matrix() {
        // [[1, 0, 2], [0, 0, 3]] as dense rows, CSR columns.
        let sp = Sparsity {
            traversal_order: vec![0, 1],
            block_map: vec![],
            dim_metadata: vec![
                DimMeta::Dense(2),
                DimMeta::SparseCsr {
                    segments: vec![0, 2, 3],
                    indices: vec![0, 2, 2],
                },
            ],
        };
        let out = sp.densify(&[2, 3], &f32s(&[1.0, 2.0, 3.0]), 4).unwrap();
        assert_eq!(out, f32s(&[1.0, 0.0, 2.0, 0.0, 0.0, 3.0]));
    }

    #[test]
    fn blocked_csr() {
        // 2x4 matrix with 1x2 blocks along dim 1; only the second block of row 0
        // and the first block of row 1 are stored.
        let sp = Sparsity {
            traversal_order: vec![0, 1, 2],
            block_map: vec![1],
            dim_metadata: vec![
                DimMeta::Dense(2),
                DimMeta::SparseCsr {
                    segments: vec![0, 1, 2],
                    indices: vec![1, 0],
                },
                DimMeta::Dense(2),
            ],
        };
        let out = sp
            .densify(&[2, 4], &f32s(&[1.0, 2.0, 3.0, 4.0]), 4)
            .unwrap();
        assert_eq!(out, f32s(&[0.0, 0.0, 1.0, 2.0, 3.0, 4.0, 0.0, 0.0]));
    }

    #[test]
    fn bad_segments_are_errors() {
        let sp = Sparsity {
            traversal_order: vec![0, 1],
            block_map: vec![],
            dim_metadata: vec![
                DimMeta::Dense(2),
                DimMeta::SparseCsr {
                    segments: vec![0, 9],
                    indices: vec![0],
                },
            ],
        };
        assert!(sp.densify(&[2, 3], &f32s(&[1.0]), 4).is_err());
    }
}
