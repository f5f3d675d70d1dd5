//! Channel resolution: each servo's `<Joint>.<Kind>` bound to a channel of a
//! skeleton, with a "did you mean" suggestion when it names none.

use crate::motion::Skeleton;

use super::*;

impl Rig {
    /// Binds every servo's channel to a channel index of `skeleton` (its
    /// frame-row order, as [`Skeleton::channel_names`]). The error points at
    /// the servo's `channel` value and suggests the closest channel name.
    pub fn resolve(&self, skeleton: &Skeleton) -> Result<Vec<usize>, RigError> {
        let list = skeleton.channel_list();
        self.servos
            .iter()
            .map(|s| {
                if let Some(i) = list
                    .iter()
                    .position(|&(j, k)| k == s.kind && skeleton.joints[j].name == s.joint)
                {
                    return Ok(i);
                }
                let fail = |msg: String| RigError::at(&self.file, s.channel_at, msg);
                if let Some(joint) = skeleton.joints.iter().find(|j| j.name == s.joint) {
                    let have: Vec<&str> = joint.channels.iter().map(|k| k.name()).collect();
                    return Err(fail(if have.is_empty() {
                        format!(
                            "unknown channel \"{}\": joint \"{}\" has no channels",
                            s.channel, s.joint
                        )
                    } else {
                        format!(
                            "unknown channel \"{}\": joint \"{}\" has only {}",
                            s.channel,
                            s.joint,
                            have.join(", ")
                        )
                    }));
                }
                let joints: Vec<&str> = list
                    .iter()
                    .filter(|&&(_, k)| k == s.kind)
                    .map(|&(j, _)| skeleton.joints[j].name.as_str())
                    .collect();
                let hint = closest(&s.joint, &joints)
                    .map(|j| format!(" (did you mean \"{j}.{}\"?)", s.kind))
                    .unwrap_or_default();
                Err(fail(format!("unknown channel \"{}\"{hint}", s.channel)))
            })
            .collect()
    }
}

/// The name in `names` closest to `wanted` (case-insensitive edit
/// distance), if it is close enough to be a plausible typo: at most a third
/// of `wanted`'s length, and at least 1.
pub(super) fn closest<'a>(wanted: &str, names: &[&'a str]) -> Option<&'a str> {
    let w = wanted.to_lowercase();
    let (best, d) = names
        .iter()
        .map(|n| (*n, strsim::levenshtein(&w, &n.to_lowercase())))
        .min_by_key(|&(_, d)| d)?;
    let limit = (w.chars().count() / 3).max(1);
    (d <= limit).then_some(best)
}
