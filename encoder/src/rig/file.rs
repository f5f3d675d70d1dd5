//! The rig file: TOML read into [`Rig`], every rule checked, every error
//! placed at its line and column.

use serde::Deserialize;
use std::ops::Range;
use std::path::Path;
use toml::Spanned;

use super::*;

// ---------------------------------------------------------------------------
// Errors and positions
// ---------------------------------------------------------------------------

pub use crate::located::Position;

/// A rig error: `file:line:column: message` (the readers' one located
/// error type).
pub type RigError = crate::located::LocatedError;

// Required keys are `Option`s here so that a missing key is reported at its
// table (the `toml` crate gives no position for a missing field).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    rig: Option<Spanned<RawRig>>,
    #[serde(default)]
    servo: Vec<Spanned<RawServo>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRig {
    name: Option<Spanned<String>>,
    rate_hz: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawServo {
    name: Option<Spanned<String>>,
    output: Option<Spanned<u16>>,
    channel: Option<Spanned<String>>,
    scale: Option<Spanned<f64>>,
    offset: Option<Spanned<f64>>,
    invert: Option<bool>,
    angle: Option<Spanned<Vec<f64>>>,
    pulse: Option<Spanned<Vec<f64>>>,
    neutral: Option<Spanned<f64>>,
    max_speed: Option<Spanned<f64>>,
    max_accel: Option<Spanned<f64>>,
}

fn parse_kind(s: &str) -> Option<ChannelKind> {
    ChannelKind::ALL
        .into_iter()
        .find(|k| k.name().eq_ignore_ascii_case(s))
}

impl Rig {
    /// The rig as a figure's hard limits: [`Servo::hard_limit`] of each
    /// servo, rig order.
    pub fn hard_limits(&self) -> Vec<mocap_servo::HardLimit> {
        self.servos.iter().map(Servo::hard_limit).collect()
    }

    /// The rig's digest (SPEC.md §3.6): its rig table at its rate with its
    /// hard limits' speeds and accelerations. A servo clip encoded for it
    /// carries it (section `0x80`); a figure built from it compares it.
    pub fn digest(&self) -> u32 {
        let servos: Vec<_> = self.servos.iter().map(Servo::rig_servo).collect();
        mocap_servo::HardLimits::new(&self.hard_limits())
            .digest(crate::servo_clip::rate_mhz(self), &servos)
    }

    /// Reads and parses a rig file. I/O errors have line and column 0.
    pub fn read_file(path: &Path) -> Result<Rig, RigError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| {
            RigError::at(
                &file,
                Position::default(),
                format!("cannot read rig file: {e}"),
            )
        })?;
        Rig::parse(&text, &file)
    }

    /// Parses and checks rig text. `file` is only used in error messages.
    ///
    /// Checks: no unknown keys; at least one servo; servo names and outputs
    /// unique; `channel` of the form `<Joint>.<Kind>`; `scale` finite and
    /// non-zero, `offset` finite; `angle[0] < angle[1]`, both finite; both
    /// pulses within 400..=2600 µs and different; `neutral` inside the
    /// pulse range; `rate_hz`, `max_speed`, `max_accel` finite and positive.
    pub fn parse(text: &str, file: &str) -> Result<Rig, RigError> {
        let pos = |span: Range<usize>| Position::of_byte(text, span.start);
        let err = |span: Range<usize>, msg: String| Err(RigError::at(file, pos(span), msg));
        let raw: RawFile = toml::from_str(text).map_err(|e| {
            let p = e.span().map_or(Position { line: 1, column: 1 }, pos);
            RigError::at(file, p, e.message().trim_end().to_string())
        })?;

        let Some(raw_rig) = raw.rig else {
            return Err(RigError::at(
                file,
                Position { line: 1, column: 1 },
                "missing [rig] table (with at least `name`)",
            ));
        };
        let rig_span = raw_rig.span();
        let raw_rig = raw_rig.into_inner();
        let Some(raw_name) = raw_rig.name else {
            return err(rig_span, "missing key `name` in [rig]".into());
        };
        let name = raw_name.get_ref().trim().to_string();
        if name.is_empty() {
            return err(raw_name.span(), "the rig name is empty".into());
        }
        let rate_hz = match &raw_rig.rate_hz {
            Some(r) if !(r.get_ref().is_finite() && *r.get_ref() > 0.0) => {
                return err(
                    r.span(),
                    format!(
                        "rate_hz must be a positive number of Hz, not {}",
                        r.get_ref()
                    ),
                );
            }
            Some(r) => *r.get_ref(),
            None => DEFAULT_RATE_HZ,
        };
        if raw.servo.is_empty() {
            return err(
                rig_span,
                "the rig has no servos (add [[servo]] tables)".into(),
            );
        }

        let mut servos: Vec<Servo> = Vec::with_capacity(raw.servo.len());
        let mut seen_outputs: Vec<(u16, Position)> = Vec::new();
        let mut seen_names: Vec<(String, Position)> = Vec::new();
        for s in raw.servo {
            let table_span = s.span();
            let s = s.into_inner();
            let missing = |key: &str| {
                Err(RigError::at(
                    file,
                    pos(table_span.clone()),
                    format!("missing key `{key}` in [[servo]]"),
                ))
            };
            let Some(name_v) = s.name else {
                return missing("name");
            };
            let Some(output_v) = s.output else {
                return missing("output");
            };
            let Some(channel_v) = s.channel else {
                return missing("channel");
            };
            let Some(angle_v) = s.angle else {
                return missing("angle");
            };
            let Some(pulse_v) = s.pulse else {
                return missing("pulse");
            };

            let sname = name_v.get_ref().trim().to_string();
            if sname.is_empty() {
                return err(name_v.span(), "the servo name is empty".into());
            }
            if let Some((_, first)) = seen_names.iter().find(|(n, _)| *n == sname) {
                return err(
                    name_v.span(),
                    format!(
                        "duplicate servo name \"{sname}\" (first used at line {})",
                        first.line
                    ),
                );
            }
            seen_names.push((sname.clone(), pos(name_v.span())));

            let output = *output_v.get_ref();
            if let Some((_, first)) = seen_outputs.iter().find(|(o, _)| *o == output) {
                return err(
                    output_v.span(),
                    format!(
                        "output {output} is already used (line {}): outputs must be unique",
                        first.line
                    ),
                );
            }
            seen_outputs.push((output, pos(output_v.span())));

            let chan = channel_v.get_ref().trim();
            let Some((joint, kind_str)) = chan.rsplit_once('.') else {
                return err(
                    channel_v.span(),
                    format!(
                        "channel \"{chan}\" is not of the form \"<Joint>.<Kind>\" (e.g. \"Neck.Yrotation\")"
                    ),
                );
            };
            let Some(kind) = parse_kind(kind_str) else {
                return err(
                    channel_v.span(),
                    format!(
                        "unknown channel kind \"{kind_str}\" in \"{chan}\" (expected one of Xposition, Yposition, Zposition, Xrotation, Yrotation, Zrotation)"
                    ),
                );
            };
            if joint.is_empty() {
                return err(
                    channel_v.span(),
                    format!("channel \"{chan}\" has no joint name before the '.'"),
                );
            }

            let scale = match &s.scale {
                Some(v) if !v.get_ref().is_finite() || *v.get_ref() == 0.0 => {
                    return err(
                        v.span(),
                        format!("scale must be finite and non-zero, not {}", v.get_ref()),
                    );
                }
                Some(v) => *v.get_ref(),
                None => 1.0,
            };
            let offset = match &s.offset {
                Some(v) if !v.get_ref().is_finite() => {
                    return err(
                        v.span(),
                        format!("offset must be finite, not {}", v.get_ref()),
                    );
                }
                Some(v) => *v.get_ref(),
                None => 0.0,
            };

            let angle = match angle_v.get_ref()[..] {
                [a, b] if a.is_finite() && b.is_finite() && a < b => [a, b],
                ref v => {
                    return err(
                        angle_v.span(),
                        format!("bad angle range {v:?}: need [lo, hi], finite, lo < hi (degrees)"),
                    );
                }
            };
            let pulse = match pulse_v.get_ref()[..] {
                [a, b] => [a, b],
                ref v => {
                    return err(
                        pulse_v.span(),
                        format!("bad pulse range {v:?}: need [at_lo, at_hi] in µs"),
                    );
                }
            };
            if let Some(bad) = pulse
                .iter()
                .find(|p| !(p.is_finite() && (MIN_PULSE_US..=MAX_PULSE_US).contains(*p)))
            {
                return err(
                    pulse_v.span(),
                    format!("pulse {bad} µs is outside {MIN_PULSE_US}..={MAX_PULSE_US} µs"),
                );
            }
            if pulse[0] == pulse[1] {
                return err(
                    pulse_v.span(),
                    format!(
                        "bad pulse range [{}, {}]: the two pulses must differ",
                        pulse[0], pulse[1]
                    ),
                );
            }
            let (pmin, pmax) = (pulse[0].min(pulse[1]), pulse[0].max(pulse[1]));
            let neutral = match &s.neutral {
                Some(n) if !(n.get_ref().is_finite() && (pmin..=pmax).contains(n.get_ref())) => {
                    return err(
                        n.span(),
                        format!(
                            "neutral {} µs is outside the pulse range {pmin}..={pmax} µs",
                            n.get_ref()
                        ),
                    );
                }
                Some(n) => *n.get_ref(),
                None => 0.5 * (pulse[0] + pulse[1]),
            };

            let positive =
                |v: &Option<Spanned<f64>>, what: &str| -> Result<Option<f64>, RigError> {
                    match v {
                        Some(x) if !(x.get_ref().is_finite() && *x.get_ref() > 0.0) => {
                            Err(RigError::at(
                                file,
                                pos(x.span()),
                                format!("{what} must be positive and finite, not {}", x.get_ref()),
                            ))
                        }
                        Some(x) => Ok(Some(*x.get_ref())),
                        None => Ok(None),
                    }
                };
            let max_speed = positive(&s.max_speed, "max_speed (deg/s)")?;
            let max_accel = positive(&s.max_accel, "max_accel (deg/s²)")?;

            servos.push(Servo {
                name: sname,
                output,
                channel: format!("{joint}.{}", kind.name()),
                joint: joint.to_string(),
                kind,
                scale,
                offset,
                invert: s.invert.unwrap_or(false),
                angle,
                pulse,
                neutral,
                max_speed,
                max_accel,
                channel_at: pos(channel_v.span()),
            });
        }
        Ok(Rig {
            file: file.to_string(),
            name,
            rate_hz,
            servos,
        })
    }
}
