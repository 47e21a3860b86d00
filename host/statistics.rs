//! Order statistics of repeated timings. Figures are medians, not means: on a noisy machine one
//! slow repeat should not move a reported time.

/// A sample, sorted.
pub struct Sorted(Vec<f64>);

impl Sorted {
    /// Sorts `sample`, which must not be empty.
    pub fn new(mut sample: Vec<f64>) -> Self {
        assert!(!sample.is_empty(), "order statistics of an empty sample");
        sample.sort_by(f64::total_cmp);
        Self(sample)
    }

    /// The value of nearest rank at quantile `q` in [0, 1].
    pub fn quantile(&self, q: f64) -> f64 {
        self.0[((self.0.len() - 1) as f64 * q).round() as usize]
    }

    /// The median: the middle value, or the mean of the middle two.
    pub fn median(&self) -> f64 {
        let n = self.0.len();
        0.5 * (self.0[(n - 1) / 2] + self.0[n / 2])
    }

    pub fn min(&self) -> f64 {
        self.0[0]
    }

    pub fn max(&self) -> f64 {
        self.0[self.0.len() - 1]
    }
}

#[cfg(test)]
mod tests {
    use super::Sorted;

    #[test]
    fn the_median_is_the_middle_value_or_the_mean_of_the_middle_two() {
        let odd = Sorted::new(vec![9.0, 1.0, 3.0]);
        assert_eq!((odd.median(), odd.min(), odd.max()), (3.0, 1.0, 9.0));
        assert_eq!(Sorted::new(vec![4.0, 1.0, 100.0, 2.0]).median(), 3.0);
        assert_eq!(Sorted::new(vec![7.0]).median(), 7.0);
        let ranks = Sorted::new((0..11).map(f64::from).rev().collect());
        assert_eq!((ranks.quantile(0.1), ranks.quantile(0.9)), (1.0, 9.0));
    }
}
