//! Adaptive segmentation of one node (Gu, Peng & Deng 2008, Algorithm 1):
//! a segment grows frame by frame and is cut before a frame whose weighted
//! change exceeds `θ` times the segment's average weighted frame change.
//! The weights are the inverse of each channel's tolerance, so a channel
//! with a tighter bound (a foot, by default) cuts sooner: the papers'
//! local distortion control.

/// The segmentation's parameters.
#[derive(Clone, Copy, Debug)]
pub struct SegmentParams {
    /// Cut when a frame's change exceeds `theta` × the segment's mean.
    pub theta: f64,
    /// Shortest segment, frames (except a take shorter than this).
    pub min_len: usize,
    /// Longest segment, frames.
    pub max_len: usize,
    /// A frame whose change exceeds `jump` × the take's mean change starts
    /// a segment whatever the segment's length (a discontinuity: the
    /// first frame of many BVH exports is a reference pose).
    pub jump: f64,
}

impl SegmentParams {
    /// The defaults at `fps` frames per second: `θ = 2`, segments of 0.1 s
    /// to 2 s.
    pub fn at_rate(fps: f64) -> SegmentParams {
        let frames = |s: f64| ((s * fps).round() as usize).max(2);
        SegmentParams {
            theta: 2.0,
            min_len: frames(0.1),
            max_len: frames(2.0).min(mocap_decoder::pattern::MAX_SEGMENT as usize),
            jump: 10.0,
        }
    }
}

/// The segments' start frames (the first is 0) of the node whose channels
/// are `x` (`[channel][frame]`, tolerance units: each channel divided by
/// its tolerance), over `frames` frames.
pub fn segment(x: &[Vec<f64>], frames: usize, p: &SegmentParams) -> Vec<usize> {
    // change[t - 1]: the weighted change into frame t.
    let change: Vec<f64> = (1..frames)
        .map(|t| x.iter().map(|c| (c[t] - c[t - 1]).abs()).sum())
        .collect();
    let overall = change.iter().sum::<f64>() / (frames.max(2) - 1) as f64;
    let mut starts = vec![0];
    let (mut start, mut sum, mut count) = (0usize, 0.0f64, 0usize);
    for (t, &d) in (1..frames).zip(&change) {
        let len = t - start;
        let mean = if count > 0 {
            sum / count as f64
        } else {
            overall
        };
        let cut = len >= p.min_len && d > p.theta * mean;
        if len >= p.max_len || cut || (overall > 0.0 && d > p.jump * overall) {
            starts.push(t);
            start = t;
            sum = 0.0;
            count = 0;
        }
        sum += d;
        count += 1;
    }
    // A last segment shorter than the shortest joins the one before, when
    // the two together are not too long.
    if starts.len() > 1 {
        let last = starts[starts.len() - 1];
        let before = starts[starts.len() - 2];
        if frames - last < p.min_len && frames - before <= p.max_len {
            starts.pop();
        }
    }
    starts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_burst_after_calm_starts_a_segment() {
        // Calm for 20 frames (change 1 a frame), then fast (change 10).
        let c: Vec<f64> = (0..40)
            .map(|t| {
                if t < 20 {
                    t as f64
                } else {
                    20.0 + 10.0 * (t - 20) as f64
                }
            })
            .collect();
        let p = SegmentParams {
            theta: 2.0,
            min_len: 5,
            max_len: 100,
            jump: 100.0,
        };
        assert_eq!(segment(&[c], 40, &p), vec![0, 21]);
    }

    #[test]
    fn segments_are_cut_at_the_longest_and_the_tail_joins() {
        let c = vec![0.0; 25];
        let p = SegmentParams {
            theta: 2.0,
            min_len: 4,
            max_len: 10,
            jump: 100.0,
        };
        // 0..10, 10..20, then 20..25 (5 ≥ 4 frames) stays alone.
        assert_eq!(segment(std::slice::from_ref(&c), 25, &p), vec![0, 10, 20]);
        // 22 frames: the tail of 2 cannot join (12 > 10) and stays.
        assert_eq!(segment(&[c[..22].to_vec()], 22, &p), vec![0, 10, 20]);
        let p = SegmentParams { max_len: 12, ..p };
        assert_eq!(segment(&[c[..22].to_vec()], 22, &p), vec![0, 12]);
    }

    #[test]
    fn a_discontinuity_cuts_even_a_short_segment() {
        // A reference pose in frame 0, then a slow ramp.
        let c: Vec<f64> = (0..30)
            .map(|t| if t == 0 { 500.0 } else { t as f64 })
            .collect();
        let p = SegmentParams {
            theta: 2.0,
            min_len: 5,
            max_len: 100,
            jump: 10.0,
        };
        assert_eq!(segment(&[c], 30, &p), vec![0, 1]);
    }
}
