//! CLIP's byte-level BPE tokenizer, built from SD's `tokenizer/merges.txt` the
//! way OpenAI's CLIP builds its vocabulary (256 byte symbols, the same with the
//! end-of-word mark `</w>`, one token per merge, then the two special tokens).

use std::collections::HashMap;
use std::path::Path;

use crate::DiffuseError;

/// Sequence length of SD's text encoder.
pub const MAX_LEN: usize = 77;

/// Tokenizes prompts into CLIP token ids, padded to [`MAX_LEN`].
#[derive(Debug, Clone)]
pub struct ClipTokenizer {
    ranks: HashMap<(String, String), usize>,
    vocab: HashMap<String, u32>,
    byte_char: [char; 256],
    bos: u32,
    eos: u32,
}

impl ClipTokenizer {
    /// Reads a `merges.txt` (first line a `#version` header).
    pub fn from_merges_file(path: &Path) -> Result<Self, DiffuseError> {
        let text = std::fs::read_to_string(path).map_err(|e| DiffuseError::bad_model(path, e))?;
        Self::from_merges(&text).map_err(|e| DiffuseError::bad_model(path, e))
    }

    /// Builds the tokenizer from the text of `merges.txt`.
    pub fn from_merges(text: &str) -> Result<Self, String> {
        let byte_char = bytes_to_unicode();
        // CLIP lists the printable bytes first, then the remapped ones.
        let order: Vec<char> = (0..256usize)
            .filter(|&b| is_printable(b as u32))
            .chain((0..256usize).filter(|&b| !is_printable(b as u32)))
            .map(|b| byte_char[b])
            .collect();
        let mut vocab_list: Vec<String> = order.iter().map(|c| c.to_string()).collect();
        vocab_list.extend(order.iter().map(|c| format!("{c}</w>")));
        let mut ranks = HashMap::new();
        for (i, line) in text
            .lines()
            .filter(|l| !l.starts_with("#version"))
            .enumerate()
        {
            if line.trim().is_empty() {
                continue;
            }
            let mut parts = line.split(' ');
            let (Some(a), Some(b), None) = (parts.next(), parts.next(), parts.next()) else {
                return Err(format!("merge line {} is not two symbols: {line:?}", i + 1));
            };
            ranks.insert((a.to_string(), b.to_string()), ranks.len());
            vocab_list.push(format!("{a}{b}"));
        }
        if ranks.is_empty() {
            return Err("no merges".into());
        }
        vocab_list.push("<|startoftext|>".into());
        vocab_list.push("<|endoftext|>".into());
        let n = vocab_list.len() as u32;
        let vocab = vocab_list.into_iter().zip(0u32..).collect();
        Ok(Self {
            ranks,
            vocab,
            byte_char,
            bos: n - 2,
            eos: n - 1,
        })
    }

    /// Token ids of `text`: start token, at most 75 text tokens, end token,
    /// then end tokens up to [`MAX_LEN`] (SD 1.5 pads with `<|endoftext|>`).
    pub fn encode(&self, text: &str) -> Vec<u32> {
        let clean = text
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
            .to_lowercase();
        let mut ids = vec![self.bos];
        for word in pre_tokenize(&clean) {
            match word.as_str() {
                "<|startoftext|>" => ids.push(self.bos),
                "<|endoftext|>" => ids.push(self.eos),
                _ => {
                    let chars: String = word.bytes().map(|b| self.byte_char[b as usize]).collect();
                    for piece in self.bpe(&chars) {
                        if let Some(&id) = self.vocab.get(&piece) {
                            ids.push(id);
                        }
                    }
                }
            }
        }
        ids.truncate(MAX_LEN - 1);
        ids.push(self.eos);
        ids.resize(MAX_LEN, self.eos);
        ids
    }

    fn bpe(&self, word: &str) -> Vec<String> {
        let chars: Vec<char> = word.chars().collect();
        let mut parts: Vec<String> = chars.iter().map(|c| c.to_string()).collect();
        if let Some(last) = parts.last_mut() {
            last.push_str("</w>");
        }
        loop {
            let best = parts
                .windows(2)
                .filter_map(|w| self.ranks.get(&(w[0].clone(), w[1].clone())))
                .min()
                .copied();
            let Some(rank) = best else { break };
            let mut merged = Vec::with_capacity(parts.len());
            let mut i = 0;
            while i < parts.len() {
                if i + 1 < parts.len()
                    && self.ranks.get(&(parts[i].clone(), parts[i + 1].clone())) == Some(&rank)
                {
                    merged.push(format!("{}{}", parts[i], parts[i + 1]));
                    i += 2;
                } else {
                    merged.push(parts[i].clone());
                    i += 1;
                }
            }
            parts = merged;
        }
        parts
    }
}

fn is_printable(b: u32) -> bool {
    (33..=126).contains(&b) || (161..=172).contains(&b) || (174..=255).contains(&b)
}

/// GPT-2's reversible map from bytes to printable characters.
fn bytes_to_unicode() -> [char; 256] {
    let mut out = ['\0'; 256];
    let mut extra = 0;
    for b in 0..256u32 {
        out[b as usize] = if is_printable(b) {
            char::from_u32(b).unwrap_or('?')
        } else {
            extra += 1;
            char::from_u32(255 + extra).unwrap_or('?')
        };
    }
    out
}

/// CLIP's split pattern: special tokens, contractions, letter runs, single
/// digits, runs of other non-space symbols.
fn pre_tokenize(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let chars: Vec<char> = text.chars().collect();
    let mut i = 0;
    let other = |c: char| !c.is_whitespace() && !c.is_alphabetic() && !c.is_numeric();
    while i < chars.len() {
        let rest: String = chars[i..chars.len().min(i + 15)].iter().collect();
        if let Some(sp) = ["<|startoftext|>", "<|endoftext|>"]
            .iter()
            .find(|s| rest.starts_with(**s))
        {
            out.push(sp.to_string());
            i += sp.chars().count();
            continue;
        }
        if let Some(c) = ["'s", "'t", "'re", "'ve", "'m", "'ll", "'d"]
            .iter()
            .find(|s| rest.starts_with(**s))
        {
            out.push(c.to_string());
            i += c.len();
            continue;
        }
        let c = chars[i];
        let start = i;
        if c.is_alphabetic() {
            while i < chars.len() && chars[i].is_alphabetic() {
                i += 1;
            }
        } else if c.is_numeric() {
            i += 1;
        } else if other(c) {
            while i < chars.len() && other(chars[i]) {
                i += 1;
            }
        } else {
            i += 1;
            continue;
        }
        out.push(chars[start..i].iter().collect());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_like_clip_pattern() {
        assert_eq!(
            pre_tokenize("it's 2 legs!!, ok"),
            vec!["it", "'s", "2", "legs", "!!,", "ok"]
        );
    }

    #[test]
    fn byte_map_is_a_bijection() {
        let m = bytes_to_unicode();
        let set: std::collections::HashSet<char> = m.iter().copied().collect();
        assert_eq!(set.len(), 256);
        assert_eq!(m[b'a' as usize], 'a');
        assert_eq!(m[b' ' as usize], '\u{120}');
    }

    #[test]
    fn rejects_a_file_without_merges() {
        assert!(ClipTokenizer::from_merges("#version: 0.2\n").is_err());
    }
}
