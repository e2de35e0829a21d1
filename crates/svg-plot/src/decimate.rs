//! Decimation per pixel column: of every run of consecutive samples in the same column, only
//! those that shape the drawn line (first, last, lowest, highest; for tracks also leftmost and
//! rightmost) reach plotters.

use crate::Polyline;
use crate::series::Sample;

/// Line decimation: splits at gaps, and keeps, of every run of consecutive samples falling into
/// the same `bucket`, the first, the last, the lowest and the highest, and for tracks (where x
/// may go back and forth within a bucket) the leftmost and the rightmost, in their original order.
/// When x increases, the leftmost and rightmost are the first and last: at most four per run.
pub(crate) fn decimate_line(samples: &[Sample], bucket: impl Fn(f64) -> i64) -> Vec<Polyline> {
    let mut segs = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    let mut i = 0;
    while i < samples.len() {
        let Some((x, _, _)) = samples[i] else {
            if !cur.is_empty() {
                segs.push(std::mem::take(&mut cur));
            }
            i += 1;
            continue;
        };
        let b = bucket(x);
        let (mut imin, mut imax, mut ileft, mut iright, mut j) = (i, i, i, i, i + 1);
        let at = |k: usize| samples[k].unwrap_or_default();
        while let Some(Some((xj, yj, _))) = samples.get(j) {
            if bucket(*xj) != b {
                break;
            }
            if *yj < at(imin).1 {
                imin = j;
            }
            if *yj > at(imax).1 {
                imax = j;
            }
            if *xj < at(ileft).0 {
                ileft = j;
            }
            if *xj > at(iright).0 {
                iright = j;
            }
            j += 1;
        }
        let mut keep = [i, imin, imax, ileft, iright, j - 1];
        keep.sort_unstable();
        for (k, &idx) in keep.iter().enumerate() {
            if k == 0 || idx != keep[k - 1] {
                let (x, y, _) = samples[idx].unwrap_or_default();
                cur.push((x, y));
            }
        }
        i = j;
    }
    if !cur.is_empty() {
        segs.push(cur);
    }
    segs
}

/// Band decimation: splits at gaps (where either edge is missing) and decimates the lower and
/// the upper edge separately as lines, so every bucket keeps its lowest low and highest high.
/// Returns the pieces as (lower edge, upper edge).
pub(crate) fn decimate_band(samples: &[Sample], bucket: impl Fn(f64) -> i64) -> Vec<(Polyline, Polyline)> {
    let edge = |pick: fn(&(f64, f64, f64)) -> f64| -> Vec<Sample> {
        samples.iter().map(|s| s.map(|s| (s.0, pick(&s), pick(&s)))).collect()
    };
    let lower = decimate_line(&edge(|s| s.1), &bucket);
    let upper = decimate_line(&edge(|s| s.2), &bucket);
    lower.into_iter().zip(upper).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::*;

    #[test]
    fn decimation_keeps_bucket_extremes() {
        let mut rnd = rng(12345);
        let samples: Vec<Sample> = (0..10_000)
            .map(|i| {
                let (y, d) = (rnd() - 0.5, rnd());
                (i % 997 != 0).then_some((i as f64 * 0.01, y - d, y + d))
            })
            .collect();
        let bucket = |x: f64| (x / 100.0 * 500.0).floor() as i64;
        let lines: Vec<(f64, f64)> = decimate_line(&samples, bucket).concat();
        let (lower, upper): (Vec<Polyline>, Vec<Polyline>) = decimate_band(&samples, bucket).into_iter().unzip();
        let (lower, upper) = (lower.concat(), upper.concat());
        assert!(lines.len() <= 4 * 520 && lower.len() <= 4 * 520, "{} {}", lines.len(), lower.len());
        for b in 0..500 {
            let raw: Vec<(f64, f64, f64)> = samples.iter().flatten().copied().filter(|s| bucket(s.0) == b).collect();
            let (ymin, ymax) =
                raw.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, c), s| (a.min(s.1), c.max(s.1)));
            let kept: Vec<f64> = lines.iter().filter(|p| bucket(p.0) == b).map(|p| p.1).collect();
            assert!(kept.contains(&ymin) && kept.contains(&ymax), "bucket {b}");
            let lo = raw.iter().map(|s| s.1).fold(f64::INFINITY, f64::min);
            let hi = raw.iter().map(|s| s.2).fold(f64::NEG_INFINITY, f64::max);
            assert!(lower.iter().any(|p| bucket(p.0) == b && p.1 == lo), "bucket {b}");
            assert!(upper.iter().any(|p| bucket(p.0) == b && p.1 == hi), "bucket {b}");
        }
        // Gaps split the line; x order is preserved.
        assert_eq!(decimate_line(&samples, bucket).len(), 11);
        assert!(lines.windows(2).all(|w| w[0].0 <= w[1].0));
        // Sparse data is kept as is.
        let few: Vec<Sample> = (0..10).map(|i| Some((i as f64, i as f64, i as f64))).collect();
        assert_eq!(decimate_line(&few, bucket).concat().len(), 10);
    }
}
