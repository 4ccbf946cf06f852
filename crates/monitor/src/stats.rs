//! The statistics of the monitor and of the study's tables and reports, in
//! one place: the detector's robust median and MAD, the reports' median
//! with its range, and the Wilson interval of a share.

/// The lower median: the middle value, or of an even count the lower of
/// the two middle ones (an element of `values`, found in O(n) by
/// reordering them); 0 when empty. The detector's robust statistics use it.
pub fn lower_median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mid = (values.len() - 1) / 2;
    *values.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// The lower median of `values` and their median absolute deviation from
/// it (the lower median of |v - median|); `values` is left holding the
/// deviations.
pub fn median_and_mad(values: &mut [f64]) -> (f64, f64) {
    let median = lower_median(values);
    for v in values.iter_mut() {
        *v = (*v - median).abs();
    }
    (median, lower_median(values))
}

/// Median, smallest and largest of the values `keep` keeps (None when it
/// keeps none). Of an even count the median is the mean of the two middle
/// values.
fn spread_of(values: impl Iterator<Item = f64>, keep: fn(&f64) -> bool) -> Option<(f64, f64, f64)> {
    let mut v: Vec<f64> = values.filter(keep).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let median = if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    };
    Some((median, v[0], v[n - 1]))
}

/// Median, smallest and largest of the finite values (None when there are
/// none). Of an even count the median is the mean of the two middle values.
pub fn spread(values: impl Iterator<Item = f64>) -> Option<(f64, f64, f64)> {
    spread_of(values, |x| x.is_finite())
}

/// The median of the finite values, as `spread` takes it (None when there are none).
pub fn median(values: &[f64]) -> Option<f64> {
    spread(values.iter().copied()).map(|s| s.0)
}

/// The median of every value but NaN, infinities included (a time that
/// never came counts as later than any); None when there are none.
pub fn median_with_infinities(values: &[f64]) -> Option<f64> {
    spread_of(values.iter().copied(), |x| !x.is_nan()).map(|s| s.0)
}

/// The 95 % Wilson score interval of a share k of n ([0, 1] when n = 0).
pub fn wilson(k: usize, n: usize) -> [f64; 2] {
    if n == 0 {
        return [0.0, 1.0];
    }
    let z = 1.959_963_984_540_054_f64;
    let (k, n) = (k as f64, n as f64);
    let p = k / n;
    let centre = (p + z * z / (2.0 * n)) / (1.0 + z * z / n);
    let half = z / (1.0 + z * z / n) * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt();
    [(centre - half).max(0.0), (centre + half).min(1.0)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lower_median_picks_the_lower_middle_element() {
        assert_eq!(lower_median(&mut []), 0.0);
        assert_eq!(lower_median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(lower_median(&mut [4.0, 1.0, 3.0, 2.0]), 2.0);
    }

    #[test]
    fn mad_is_the_lower_median_of_the_deviations() {
        let mut v = [1.0, 2.0, 3.0, 4.0, 100.0];
        assert_eq!(median_and_mad(&mut v), (3.0, 1.0));
    }

    #[test]
    fn spread_skips_non_finite_values_and_averages_an_even_middle() {
        let v = [f64::NAN, 10.0, 1.0, 3.0, 2.0, f64::INFINITY];
        assert_eq!(spread(v.iter().copied()), Some((2.5, 1.0, 10.0)));
        assert_eq!(median(&[f64::NAN]), None);
        assert_eq!(median(&[5.0, 1.0, 3.0]), Some(3.0));
        assert_eq!(
            median_with_infinities(&[3.0, 1.0, f64::INFINITY, 2.0, f64::NAN]),
            Some(2.5)
        );
        assert_eq!(median_with_infinities(&[f64::NAN]), None);
    }

    #[test]
    fn the_wilson_interval_matches_its_closed_form() {
        // 4 of 5: the textbook values 0.376 and 0.964.
        let [lo, hi] = wilson(4, 5);
        assert!(
            (lo - 0.3755).abs() < 1e-3 && (hi - 0.9638).abs() < 1e-3,
            "{lo} {hi}"
        );
        let [lo, hi] = wilson(0, 5);
        assert_eq!(lo, 0.0);
        assert!((hi - 0.4345).abs() < 1e-3, "{hi}");
        assert_eq!(wilson(0, 0), [0.0, 1.0]);
    }
}
