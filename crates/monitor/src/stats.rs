//! The statistics of the monitor and of the study's tables and reports, in
//! one place: the detector's robust median and MAD, and the reports' median
//! with its range.

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

/// Median, smallest and largest of the finite values (None when there are
/// none). Of an even count the median is the mean of the two middle values.
pub fn spread(values: impl Iterator<Item = f64>) -> Option<(f64, f64, f64)> {
    let mut v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
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

/// The median of the finite values, as `spread` takes it (None when there are none).
pub fn median(values: &[f64]) -> Option<f64> {
    spread(values.iter().copied()).map(|s| s.0)
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
    }
}
