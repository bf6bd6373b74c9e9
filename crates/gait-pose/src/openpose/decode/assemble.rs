//! Part-affinity scoring of candidate limbs, greedy matching, and grouping
//! of the matched limbs into people, as controlnet_aux's `Body.__call__`
//! does it (same order, same ties, same merge and deletion rules).

use super::limbs::Limb;
use super::peaks::Peak;

/// Thresholds of the grouping (see `SearchParams`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct AssembleParams {
    pub thresh2: f64,
    pub mid_num: usize,
    pub min_parts: f64,
    pub min_mean_score: f64,
}

/// A matched limb: peak ids at both ends and its PAF score.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Connection {
    id_a: usize,
    id_b: usize,
    score: f64,
}

/// `np.linspace(a, b, num)` for integer end points.
fn linspace(a: usize, b: usize, num: usize) -> Vec<f64> {
    let (a, b) = (a as f64, b as f64);
    if num <= 1 {
        return vec![a; num];
    }
    let div = (num - 1) as f64;
    let step = (b - a) / div;
    let mut y: Vec<f64> = (0..num)
        .map(|i| {
            if step == 0.0 {
                (i as f64 / div) * (b - a) + a
            } else {
                i as f64 * step + a
            }
        })
        .collect();
    y[num - 1] = b;
    y
}

/// Scores every candidate pair of one limb on its PAF (x and y planes of
/// `width` x `height`) and keeps the best disjoint ones, highest first.
pub(crate) fn connect(
    cand_a: &[Peak],
    cand_b: &[Peak],
    paf_x: &[f64],
    paf_y: &[f64],
    width: usize,
    height: usize,
    p: &AssembleParams,
) -> Vec<Connection> {
    let mut candidates: Vec<(usize, usize, f64)> = Vec::new();
    let sample = |plane: &[f64], x: f64, y: f64| -> f64 {
        let xi = (x.round_ties_even().max(0.0) as usize).min(width.saturating_sub(1));
        let yi = (y.round_ties_even().max(0.0) as usize).min(height.saturating_sub(1));
        plane.get(yi * width + xi).copied().unwrap_or(f64::NAN)
    };
    for (i, a) in cand_a.iter().enumerate() {
        for (j, b) in cand_b.iter().enumerate() {
            let dx = b.x as f64 - a.x as f64;
            let dy = b.y as f64 - a.y as f64;
            let norm = (dx * dx + dy * dy).sqrt().max(0.001);
            let (vx, vy) = (dx / norm, dy / norm);
            let xs = linspace(a.x, b.x, p.mid_num);
            let ys = linspace(a.y, b.y, p.mid_num);
            let mut sum = 0.0;
            let mut above = 0usize;
            for (x, y) in xs.iter().zip(&ys) {
                let s = sample(paf_x, *x, *y) * vx + sample(paf_y, *x, *y) * vy;
                sum += s;
                if s > p.thresh2 {
                    above += 1;
                }
            }
            let prior = (0.5 * height as f64 / norm - 1.0).min(0.0);
            let score = sum / p.mid_num as f64 + prior;
            if above as f64 > 0.8 * p.mid_num as f64 && score > 0.0 {
                candidates.push((i, j, score));
            }
        }
    }
    // Stable, so equal scores keep their (i, j) order, as Python's sorted(reverse=True).
    candidates.sort_by(|x, y| y.2.partial_cmp(&x.2).unwrap_or(std::cmp::Ordering::Equal));
    let limit = cand_a.len().min(cand_b.len());
    let mut used_a = vec![false; cand_a.len()];
    let mut used_b = vec![false; cand_b.len()];
    let mut out = Vec::new();
    for (i, j, score) in candidates {
        if !used_a[i] && !used_b[j] {
            used_a[i] = true;
            used_b[j] = true;
            out.push(Connection {
                id_a: cand_a[i].id,
                id_b: cand_b[j].id,
                score,
            });
            if out.len() >= limit {
                break;
            }
        }
    }
    out
}

/// A person under construction: peak id per keypoint, total score and count
/// (floats, as controlnet_aux's `subset` rows, to sum in the same order).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Row {
    pub parts: Vec<Option<usize>>,
    pub score: f64,
    pub count: f64,
}

/// Groups the connections of every limb (`None` where a limb had no
/// candidates at one end) into people; `peak_score[id]` is each peak's score.
pub(crate) fn group(
    limbs: &[Limb],
    connections: &[Option<Vec<Connection>>],
    peak_score: &[f64],
    n_parts: usize,
    p: &AssembleParams,
) -> Vec<Row> {
    let mut rows: Vec<Row> = Vec::new();
    for (limb, conns) in limbs.iter().zip(connections) {
        let Some(conns) = conns else { continue };
        let (ia, ib) = (limb.a, limb.b);
        for c in conns {
            let mut found = 0usize;
            let mut idx = [0usize; 2];
            for (j, r) in rows.iter().enumerate() {
                if r.parts[ia] == Some(c.id_a) || r.parts[ib] == Some(c.id_b) {
                    // controlnet_aux raises IndexError on a third match; we
                    // leave such a connection out instead.
                    if found < 2 {
                        idx[found] = j;
                    }
                    found += 1;
                }
            }
            let score_b = peak_score[c.id_b];
            match found {
                1 => {
                    let r = &mut rows[idx[0]];
                    if r.parts[ib] != Some(c.id_b) {
                        r.parts[ib] = Some(c.id_b);
                        r.count += 1.0;
                        r.score += score_b + c.score;
                    }
                }
                2 => {
                    let (j1, j2) = (idx[0], idx[1]);
                    let overlap = rows[j1]
                        .parts
                        .iter()
                        .zip(&rows[j2].parts)
                        .any(|(x, y)| x.is_some() && y.is_some());
                    if !overlap {
                        let other = rows[j2].clone();
                        let r = &mut rows[j1];
                        for (x, y) in r.parts.iter_mut().zip(&other.parts) {
                            if y.is_some() {
                                *x = *y;
                            }
                        }
                        r.score += other.score;
                        r.count += other.count;
                        r.score += c.score;
                        rows.remove(j2);
                    } else {
                        let r = &mut rows[j1];
                        r.parts[ib] = Some(c.id_b);
                        r.count += 1.0;
                        r.score += score_b + c.score;
                    }
                }
                0 if limb.starts_person => {
                    let mut parts = vec![None; n_parts];
                    parts[ia] = Some(c.id_a);
                    parts[ib] = Some(c.id_b);
                    rows.push(Row {
                        parts,
                        score: 0.0 + peak_score[c.id_a] + score_b + c.score,
                        count: 2.0,
                    });
                }
                _ => {}
            }
        }
    }
    rows.retain(|r| !(r.count < p.min_parts || r.score / r.count < p.min_mean_score));
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linspace_matches_numpy_end_points() {
        assert_eq!(linspace(3, 3, 4), vec![3.0; 4]);
        let v = linspace(0, 9, 10);
        assert_eq!(v, (0..10).map(|i| i as f64).collect::<Vec<_>>());
    }
}
