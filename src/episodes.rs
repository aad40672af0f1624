//! Aggregation of finished episodes as the paper's table does it (docs/spec.md 8.3): every
//! statistic of
//! [`crate::spec::EPISODE_KEYS`] averaged over episodes, plus outcome rates.

use crate::spec::{EPISODE_KEYS, N_EPISODE};

/// The statistics of the paper's table (docs/spec.md 8.3) in the order `socnav run` reports them:
/// the info metrics of docs/spec.md 8.2 as episode statistics, then the table's own columns.
pub const TABLE_KEYS: [&str; 24] = [
    "STL",
    "SPL",
    "PATH_LENGTH",
    "PERSONAL_SPACE_COMPLIANCE",
    "FAILURE_TO_PROGRESS",
    "STALLED_TIME",
    "TIME_TO_REACH_GOAL",
    "V_MIN",
    "V_AVG",
    "V_MAX",
    "A_MIN",
    "A_AVG",
    "A_MAX",
    "JERK_MIN",
    "JERK_AVG",
    "JERK_MAX",
    "MINIMUM_DISTANCE_TO_HUMAN",
    "MINIMUM_OBSTACLE_DISTANCE",
    "AVERAGE_OBSTACLE_DISTANCE",
    "TIME_TO_COLLISION",
    "DISCOMFORT_DSRNN",
    "DISCOMFORT_SNGNN",
    "time_taken",
    "return",
];

/// Running sums over finished episodes.
#[derive(Debug, Clone)]
pub struct Aggregate {
    episodes: u64,
    sums: [f64; N_EPISODE],
    /// Episodes in which each statistic was finite (minimum distances are +inf without humans or
    /// obstacles; those episodes do not count towards that mean).
    finite: [u64; N_EPISODE],
}

impl Default for Aggregate {
    fn default() -> Self {
        Self {
            episodes: 0,
            sums: [0.0; N_EPISODE],
            finite: [0; N_EPISODE],
        }
    }
}

impl Aggregate {
    /// Add one episode's statistics (one row of [`crate::outputs::Outputs::episode`]).
    pub fn add(&mut self, row: &[f32]) {
        assert_eq!(
            row.len(),
            N_EPISODE,
            "an episode row has {N_EPISODE} values"
        );
        self.episodes += 1;
        for (k, &v) in row.iter().enumerate() {
            if v.is_finite() {
                self.sums[k] += f64::from(v);
                self.finite[k] += 1;
            }
        }
    }

    /// Add every episode that ended in the last step of a batch.
    pub fn add_finished(&mut self, out: &crate::outputs::Outputs) {
        for e in 0..out.n_envs {
            if out.episode_done[e] != 0 {
                self.add(&out.episode[e * N_EPISODE..(e + 1) * N_EPISODE]);
            }
        }
    }

    /// Merge another aggregate.
    pub fn merge(&mut self, other: &Aggregate) {
        self.episodes += other.episodes;
        for k in 0..N_EPISODE {
            self.sums[k] += other.sums[k];
            self.finite[k] += other.finite[k];
        }
    }

    /// Finished episodes.
    pub fn episodes(&self) -> u64 {
        self.episodes
    }

    /// Mean of statistic `key` over the episodes where it is finite (NaN if none); `None` when
    /// `key` is none of [`EPISODE_KEYS`].
    pub fn mean(&self, key: &str) -> Option<f64> {
        let k = EPISODE_KEYS.iter().position(|k| *k == key)?;
        Some(if self.finite[k] == 0 {
            f64::NAN
        } else {
            self.sums[k] / self.finite[k] as f64
        })
    }

    /// Every statistic's mean, in [`EPISODE_KEYS`] order.
    pub fn means(&self) -> Vec<(&'static str, f64)> {
        EPISODE_KEYS
            .iter()
            .map(|k| (*k, self.mean(k).unwrap_or(f64::NAN)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn means_skip_non_finite_values() {
        let mut a = Aggregate::default();
        let mut row = [0.0f32; N_EPISODE];
        row[2] = 1.0; // success
        row[26] = f32::INFINITY; // MINIMUM_DISTANCE_TO_HUMAN without humans
        a.add(&row);
        row[2] = 0.0;
        row[26] = 2.0;
        a.add(&row);
        assert_eq!(a.episodes(), 2);
        assert_eq!(a.mean("success"), Some(0.5));
        assert_eq!(a.mean("nope"), None);
        assert_eq!(a.mean("MINIMUM_DISTANCE_TO_HUMAN"), Some(2.0));
    }
}
