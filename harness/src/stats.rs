//! Figures of the speed benches, the same for every bus (`harness/benches/`): rates, medians of
//! rounds, the jitter of a periodic stream (EtherNet/IP T→O data at its RPI, EtherCAT
//! process data at its cycle time) from its arrival times and sequence numbers, and the trend
//! of a sampled quantity (the soak's resident memory).
//!
//! Pure functions over numbers the benches measured; nothing here reads a clock.

use std::time::Duration;

/// A count over a time: requests, round trips, frames.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rate {
    /// How many.
    pub count: u64,
    /// In how many seconds.
    pub secs: f64,
}

impl Rate {
    /// The count per second; 0 over no time.
    pub fn per_sec(&self) -> f64 {
        if self.secs > 0.0 {
            self.count as f64 / self.secs
        } else {
            0.0
        }
    }

    /// `20000 round trips in 0.812 s = 24631/s`.
    pub fn show(&self, what: &str) -> String {
        format!(
            "{} {what} in {:.3} s = {:.0}/s",
            self.count,
            self.secs,
            self.per_sec()
        )
    }
}

/// The median of `values` (the mean of the middle two of an even count); `None` when empty.
pub fn median(mut values: Vec<f64>) -> Option<f64> {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(values[n / 2]),
        _ => Some((values[n / 2 - 1] + values[n / 2]) / 2.0),
    }
}

/// How far the arrivals of a periodic stream stray from its period.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Jitter {
    /// Frames received.
    pub frames: usize,
    /// Frames missing by their sequence numbers.
    pub lost: u64,
    /// Frames whose sequence number did not advance (duplicates, reordering).
    pub disordered: u64,
    /// Median of |interval − period| over consecutive sequence numbers.
    pub p50: Duration,
    /// 99th percentile of the same.
    pub p99: Duration,
    /// The largest.
    pub max: Duration,
}

/// Jitter of `arrivals` ((sequence number, arrival time), in arrival order) against `period`.
/// Only intervals between consecutive sequence numbers count; a gap counts its missing frames
/// as lost. `None` without a single such interval.
///
/// A stream without sequence numbers of its own (EtherCAT frames: the bench's own cycle
/// counter, or the datagram index) numbers its arrivals as it sends them.
pub fn jitter(arrivals: &[(u32, Duration)], period: Duration) -> Option<Jitter> {
    let (mut lost, mut disordered) = (0u64, 0u64);
    let mut deviations = Vec::with_capacity(arrivals.len());
    for pair in arrivals.windows(2) {
        let ((s0, t0), (s1, t1)) = (pair[0], pair[1]);
        match s1.wrapping_sub(s0) {
            1 => deviations.push(t1.saturating_sub(t0).abs_diff(period)),
            gap if gap > 1 && gap < 1 << 31 => lost += u64::from(gap - 1),
            _ => disordered += 1,
        }
    }
    deviations.sort_unstable();
    Some(Jitter {
        frames: arrivals.len(),
        lost,
        disordered,
        p50: percentile(&deviations, 50.0)?,
        p99: percentile(&deviations, 99.0)?,
        max: *deviations.last()?,
    })
}

/// The least-squares slope of `samples` ((x, y) pairs: seconds and KiB, for the soak's
/// memory), in y per x; `None` with fewer than two distinct x.
pub fn slope(samples: &[(f64, f64)]) -> Option<f64> {
    let n = samples.len() as f64;
    let mean = |f: fn(&(f64, f64)) -> f64| samples.iter().map(f).sum::<f64>() / n;
    let (mx, my) = (mean(|s| s.0), mean(|s| s.1));
    let sxx: f64 = samples.iter().map(|(x, _)| (x - mx).powi(2)).sum();
    let sxy: f64 = samples.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// The `p`th percentile (nearest rank) of ascending `sorted`; `None` when empty.
pub fn percentile(sorted: &[Duration], p: f64) -> Option<Duration> {
    if sorted.is_empty() {
        return None;
    }
    let rank = (p / 100.0 * sorted.len() as f64).ceil() as usize;
    sorted.get(rank.clamp(1, sorted.len()) - 1).copied()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn us(n: u64) -> Duration {
        Duration::from_micros(n)
    }

    #[test]
    fn median_of_odd_even_and_no_rounds() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(vec![4.0, 1.0, 3.0, 2.0]), Some(2.5));
        assert_eq!(median(Vec::new()), None);
    }

    #[test]
    fn a_rate_is_a_count_per_second() {
        let r = Rate {
            count: 20_000,
            secs: 0.8,
        };
        assert_eq!(r.per_sec(), 25_000.0);
        assert_eq!(
            r.show("round trips"),
            "20000 round trips in 0.800 s = 25000/s"
        );
        assert_eq!(
            Rate {
                count: 5,
                secs: 0.0
            }
            .per_sec(),
            0.0
        );
    }

    #[test]
    fn slope_is_the_least_squares_trend() {
        // Flat, rising by 2 per second, and rising with noise around 1 per second.
        assert_eq!(slope(&[(0.0, 5.0), (1.0, 5.0), (2.0, 5.0)]), Some(0.0));
        assert_eq!(slope(&[(0.0, 1.0), (1.0, 3.0), (2.0, 5.0)]), Some(2.0));
        let noisy = slope(&[(0.0, 0.0), (1.0, 2.0), (2.0, 1.0), (3.0, 3.0)]).unwrap();
        assert!((noisy - 0.8).abs() < 1e-9, "{noisy}");
        // No trend without two distinct times.
        assert_eq!(slope(&[]), None);
        assert_eq!(slope(&[(1.0, 1.0), (1.0, 9.0)]), None);
    }

    #[test]
    fn percentile_is_nearest_rank() {
        let v: Vec<Duration> = (1..=100).map(us).collect();
        assert_eq!(percentile(&v, 50.0), Some(us(50)));
        assert_eq!(percentile(&v, 99.0), Some(us(99)));
        assert_eq!(percentile(&v, 100.0), Some(us(100)));
        assert_eq!(percentile(&v, 0.0), Some(us(1)));
        // 10 values: rank ceil(9.9) = 10, the largest.
        let ten: Vec<Duration> = (1..=10).map(us).collect();
        assert_eq!(percentile(&ten, 99.0), Some(us(10)));
        assert_eq!(percentile(&ten, 50.0), Some(us(5)));
        assert_eq!(percentile(&[us(7)], 99.0), Some(us(7)));
        assert_eq!(percentile(&[], 50.0), None);
    }

    #[test]
    fn jitter_of_a_perfect_stream_is_zero() {
        let a: Vec<(u32, Duration)> = (0..10).map(|i| (i + 1, us(1000 * u64::from(i)))).collect();
        let j = jitter(&a, us(1000)).unwrap();
        assert_eq!(
            j,
            Jitter {
                frames: 10,
                lost: 0,
                disordered: 0,
                p50: Duration::ZERO,
                p99: Duration::ZERO,
                max: Duration::ZERO,
            }
        );
    }

    #[test]
    fn jitter_is_the_absolute_deviation_from_the_period() {
        // Intervals 1100, 900, 1000, 1300 µs: deviations 100, 100, 0, 300.
        let a = [
            (1, us(0)),
            (2, us(1100)),
            (3, us(2000)),
            (4, us(3000)),
            (5, us(4300)),
        ];
        let j = jitter(&a, us(1000)).unwrap();
        assert_eq!((j.p50, j.p99, j.max), (us(100), us(300), us(300)));
    }

    #[test]
    fn gaps_count_as_lost_and_are_not_intervals() {
        // 3 and 4 missing: the 3000 µs interval 2→5 is not a jitter sample.
        let a = [(1, us(0)), (2, us(1000)), (5, us(4000)), (6, us(5050))];
        let j = jitter(&a, us(1000)).unwrap();
        assert_eq!((j.frames, j.lost, j.disordered), (4, 2, 0));
        assert_eq!((j.p50, j.max), (us(0), us(50)));
    }

    #[test]
    fn sequence_numbers_wrap_and_repeats_are_disordered() {
        let a = [
            (u32::MAX, us(0)),
            (0, us(1000)),
            (0, us(1500)),
            (1, us(2000)),
        ];
        let j = jitter(&a, us(1000)).unwrap();
        assert_eq!((j.lost, j.disordered), (0, 1));
        // 0 → 1 counts from the repeat's arrival: 500 µs, deviation 500.
        assert_eq!((j.p50, j.max), (us(0), us(500)));
    }

    #[test]
    fn no_interval_no_jitter() {
        assert_eq!(jitter(&[], us(1000)), None);
        assert_eq!(jitter(&[(1, us(0))], us(1000)), None);
        assert_eq!(jitter(&[(1, us(0)), (3, us(2000))], us(1000)), None);
    }
}
