//! CLIP text encoder (transformers' `CLIPTextModel` tensor names, with or
//! without the `text_model.` level): token + position embeddings, pre-norm transformer layers
//! with a causal mask, final layer norm. Its last hidden state conditions the
//! UNet. Our own, because candle's CLIP config cannot be built for other sizes.

use candle_core::{D, DType, Device, Module, Result, Tensor};
use candle_nn::{Embedding, LayerNorm, Linear, VarBuilder, embedding, layer_norm, linear};

use crate::model_config::TextConfig;

#[derive(Debug)]
struct Layer {
    q: Linear,
    k: Linear,
    v: Linear,
    out: Linear,
    norm1: LayerNorm,
    norm2: LayerNorm,
    fc1: Linear,
    fc2: Linear,
}

/// The text transformer of CLIP.
#[derive(Debug)]
pub struct ClipTextModel {
    token: Embedding,
    position: Embedding,
    layers: Vec<Layer>,
    final_norm: LayerNorm,
    heads: usize,
    quick_gelu: bool,
}

impl ClipTextModel {
    pub fn new(vb: VarBuilder, cfg: &TextConfig) -> Result<Self> {
        // transformers < 5 (SD 1.5's file) nests everything under `text_model.`.
        let vb = if vb.contains_tensor("text_model.embeddings.token_embedding.weight") {
            vb.pp("text_model")
        } else {
            vb
        };
        let e = vb.pp("embeddings");
        let h = cfg.hidden_size;
        // The weights' shapes do not show the head count: a config must split `h` evenly.
        if cfg.num_attention_heads == 0 || !h.is_multiple_of(cfg.num_attention_heads) {
            candle_core::bail!(
                "text encoder config: {} attention heads do not divide hidden size {h}",
                cfg.num_attention_heads
            );
        }
        let token = embedding(cfg.vocab_size, h, e.pp("token_embedding"))?;
        let position = embedding(cfg.max_position_embeddings, h, e.pp("position_embedding"))?;
        let eps = cfg.layer_norm_eps;
        let layers = (0..cfg.num_hidden_layers)
            .map(|i| {
                let l = vb.pp("encoder.layers").pp(i);
                let a = l.pp("self_attn");
                Ok(Layer {
                    q: linear(h, h, a.pp("q_proj"))?,
                    k: linear(h, h, a.pp("k_proj"))?,
                    v: linear(h, h, a.pp("v_proj"))?,
                    out: linear(h, h, a.pp("out_proj"))?,
                    norm1: layer_norm(h, eps, l.pp("layer_norm1"))?,
                    norm2: layer_norm(h, eps, l.pp("layer_norm2"))?,
                    fc1: linear(h, cfg.intermediate_size, l.pp("mlp.fc1"))?,
                    fc2: linear(cfg.intermediate_size, h, l.pp("mlp.fc2"))?,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let final_norm = layer_norm(h, eps, vb.pp("final_layer_norm"))?;
        Ok(Self {
            token,
            position,
            layers,
            final_norm,
            heads: cfg.num_attention_heads,
            quick_gelu: cfg.hidden_act == "quick_gelu",
        })
    }

    /// Last hidden state (after the final layer norm) for token ids `(batch, seq)`.
    pub fn forward(&self, ids: &Tensor) -> Result<Tensor> {
        let (b, n) = ids.dims2()?;
        let pos = Tensor::arange(0u32, n as u32, ids.device())?;
        let mut x = self
            .token
            .forward(ids)?
            .broadcast_add(&self.position.forward(&pos)?)?;
        let mask = causal_mask(n, x.dtype(), x.device())?;
        let hd = x.dim(D::Minus1)? / self.heads;
        let scale = 1.0 / (hd as f64).sqrt();
        let split = |t: Tensor| -> Result<Tensor> {
            t.reshape((b, n, self.heads, hd))?
                .transpose(1, 2)?
                .contiguous()
        };
        for l in &self.layers {
            let y = l.norm1.forward(&x)?;
            let q = split((l.q.forward(&y)? * scale)?)?;
            let k = split(l.k.forward(&y)?)?;
            let v = split(l.v.forward(&y)?)?;
            let att = q.matmul(&k.t()?)?.broadcast_add(&mask)?;
            let att = candle_nn::ops::softmax_last_dim(&att)?;
            let y = att
                .matmul(&v)?
                .transpose(1, 2)?
                .reshape((b, n, self.heads * hd))?;
            x = (x + l.out.forward(&y)?)?;
            let y = l.fc1.forward(&l.norm2.forward(&x)?)?;
            let y = if self.quick_gelu {
                (&y * candle_nn::ops::sigmoid(&(&y * 1.702)?)?)?
            } else {
                y.gelu_erf()?
            };
            x = (x + l.fc2.forward(&y)?)?;
        }
        self.final_norm.forward(&x)
    }
}

fn causal_mask(n: usize, dtype: DType, device: &Device) -> Result<Tensor> {
    let m: Vec<f32> = (0..n)
        .flat_map(|i| (0..n).map(move |j| if j > i { f32::NEG_INFINITY } else { 0.0 }))
        .collect();
    Tensor::from_vec(m, (n, n), device)?.to_dtype(dtype)
}
