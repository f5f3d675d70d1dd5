//! The in-memory motion model every part of the encoder works on: a joint
//! hierarchy (skeleton) plus a frames × channels matrix of values in the
//! file's own units (lengths) and degrees (angles).

/// One BVH channel type: the decoder's own type (SPEC.md §3.2), so the two
/// sides cannot disagree. Rotations are in degrees, positions in the
/// skeleton's length unit (see [`crate::units::LengthUnit`]).
pub use mocap_decoder::ChannelKind;

/// A joint of the hierarchy. End Sites are joints with `end_site == true`
/// and no channels; they matter for forward kinematics (they are the tips
/// whose positions the error metrics measure) and for writing BVH back.
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    /// Joint name (End Sites are named `<parent>_End`).
    pub name: String,
    /// Index of the parent joint; `None` for a root.
    pub parent: Option<usize>,
    /// OFFSET from the parent, in the skeleton's length unit.
    pub offset: [f64; 3],
    /// Channels in the order the CHANNELS line lists them.
    pub channels: Vec<ChannelKind>,
    /// True for an End Site.
    pub end_site: bool,
}

/// Joint hierarchy in depth-first file order: a parent always comes before
/// its children.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Skeleton {
    /// Joints in file order.
    pub joints: Vec<Joint>,
}

impl Skeleton {
    /// Total number of channels over all joints.
    pub fn channel_count(&self) -> usize {
        self.joints.iter().map(|j| j.channels.len()).sum()
    }

    /// For each channel (in frame-row order): (joint index, kind).
    pub fn channel_list(&self) -> Vec<(usize, ChannelKind)> {
        self.joints
            .iter()
            .enumerate()
            .flat_map(|(j, joint)| joint.channels.iter().map(move |&k| (j, k)))
            .collect()
    }

    /// The kind of every channel, in frame-row order.
    pub fn channel_kinds(&self) -> Vec<ChannelKind> {
        self.joints
            .iter()
            .flat_map(|j| j.channels.iter().copied())
            .collect()
    }

    /// The joint of every channel, in frame-row order.
    pub fn channel_joints(&self) -> Vec<usize> {
        self.channel_list().into_iter().map(|(j, _)| j).collect()
    }

    /// `Joint.Kind` names of every channel, e.g. `LeftForeArm.Zrotation`.
    pub fn channel_names(&self) -> Vec<String> {
        self.channel_list()
            .into_iter()
            .map(|(j, k)| format!("{}.{}", self.joints[j].name, k))
            .collect()
    }
}

/// A motion clip: skeleton, frame time and the frames × channels matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    /// The joint hierarchy.
    pub skeleton: Skeleton,
    /// Seconds per frame (BVH `Frame Time`).
    pub frame_time: f64,
    /// Row-major values: `values[frame * channels + channel]`.
    pub values: Vec<f64>,
}

impl Motion {
    /// Number of channels per frame.
    pub fn channels(&self) -> usize {
        self.skeleton.channel_count()
    }

    /// Number of frames.
    pub fn frames(&self) -> usize {
        self.values.len().checked_div(self.channels()).unwrap_or(0)
    }

    /// One frame's values.
    pub fn frame(&self, i: usize) -> &[f64] {
        let c = self.channels();
        &self.values[i * c..(i + 1) * c]
    }

    /// One channel's values over all frames.
    pub fn channel(&self, c: usize) -> Vec<f64> {
        let n = self.channels();
        (0..self.frames()).map(|f| self.values[f * n + c]).collect()
    }
}
