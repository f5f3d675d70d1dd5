//! The ASF reader: units, root, bone data and hierarchy, as written (angles
//! converted to degrees, directions normalised).

use std::collections::HashMap;

use super::text::{column, lines, tokens, uncomment};
use super::AsfError;
use crate::units::LengthUnit;

/// The angle unit of `:units angle` (and of an AMC's `:DEGREES`/`:RADIANS`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AngleUnit {
    /// Degrees.
    Deg,
    /// Radians.
    Rad,
}

impl AngleUnit {
    /// Degrees per unit.
    pub fn degrees(self) -> f64 {
        match self {
            AngleUnit::Deg => 1.0,
            AngleUnit::Rad => 180.0 / std::f64::consts::PI,
        }
    }
}

/// `:units`: the file's factors (defaults 1, 1, degrees).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AsfUnits {
    /// `mass` factor.
    pub mass: f64,
    /// `length` factor: the file's lengths are inches × this factor (CMU:
    /// 0.45).
    pub length: f64,
    /// `angle`: `deg` or `rad`.
    pub angle: AngleUnit,
}

impl Default for AsfUnits {
    fn default() -> Self {
        AsfUnits {
            mass: 1.0,
            length: 1.0,
            angle: AngleUnit::Deg,
        }
    }
}

impl AsfUnits {
    /// The length unit this factor names: 0.45 is the CMU unit (1/0.45
    /// inch); other factors are not mapped (`None`).
    pub fn length_unit(&self) -> Option<LengthUnit> {
        ((self.length - 0.45).abs() < 1e-9).then_some(LengthUnit::Cmu)
    }
}

/// A degree of freedom of a bone (`dof`) or of the root (`order`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Dof {
    /// Rotation about X.
    Rx,
    /// Rotation about Y.
    Ry,
    /// Rotation about Z.
    Rz,
    /// Translation along X.
    Tx,
    /// Translation along Y.
    Ty,
    /// Translation along Z.
    Tz,
    /// Length change along the bone (`l`).
    L,
}

impl Dof {
    fn parse(s: &str) -> Option<Dof> {
        Some(match s.to_ascii_lowercase().as_str() {
            "rx" => Dof::Rx,
            "ry" => Dof::Ry,
            "rz" => Dof::Rz,
            "tx" => Dof::Tx,
            "ty" => Dof::Ty,
            "tz" => Dof::Tz,
            "l" => Dof::L,
            _ => return None,
        })
    }

    /// True for `rx`, `ry`, `rz`.
    pub fn is_rotation(self) -> bool {
        matches!(self, Dof::Rx | Dof::Ry | Dof::Rz)
    }

    /// The axis (0, 1, 2) of a rotation or translation; 3 for `l`.
    pub fn axis(self) -> usize {
        match self {
            Dof::Rx | Dof::Tx => 0,
            Dof::Ry | Dof::Ty => 1,
            Dof::Rz | Dof::Tz => 2,
            Dof::L => 3,
        }
    }

    /// The name as ASF writes it (`rx`, …, `l`).
    pub fn name(self) -> &'static str {
        match self {
            Dof::Rx => "rx",
            Dof::Ry => "ry",
            Dof::Rz => "rz",
            Dof::Tx => "tx",
            Dof::Ty => "ty",
            Dof::Tz => "tz",
            Dof::L => "l",
        }
    }
}

/// `:root`.
#[derive(Clone, Debug, PartialEq)]
pub struct AsfRoot {
    /// `order`: the root's dof, in the order of its AMC values.
    pub order: Vec<Dof>,
    /// `axis`: the axis order of `orientation` (0 = X, 1 = Y, 2 = Z).
    pub axis_order: [usize; 3],
    /// `position`, in the file's length unit.
    pub position: [f64; 3],
    /// `orientation` in degrees, value `i` about axis `axis_order[i]`.
    pub orientation: [f64; 3],
    /// Bones whose parent is the root, in `:hierarchy` order.
    pub children: Vec<usize>,
}

/// One `begin … end` block of `:bonedata`.
#[derive(Clone, Debug, PartialEq)]
pub struct AsfBone {
    /// `id`, if given.
    pub id: Option<i64>,
    /// `name`.
    pub name: String,
    /// `direction`, normalised, in world coordinates.
    pub direction: [f64; 3],
    /// `length`, in the file's length unit.
    pub length: f64,
    /// `axis` angles in degrees, value `i` about axis `axis_order[i]`.
    pub axis: [f64; 3],
    /// The axis order of `axis` (`XYZ` = `[0, 1, 2]`): the rotations are
    /// applied in this order.
    pub axis_order: [usize; 3],
    /// `dof`, in the order of the bone's AMC values.
    pub dof: Vec<Dof>,
    /// `limits`, one `(lo, hi)` per dof (degrees for rotations); empty when
    /// the bone has none.
    pub limits: Vec<(f64, f64)>,
    /// The parent bone; `None` for a child of the root.
    pub parent: Option<usize>,
    /// Child bones, in `:hierarchy` order.
    pub children: Vec<usize>,
    /// The line of the bone's `begin`.
    pub line: usize,
}

/// A parsed ASF file.
#[derive(Clone, Debug, PartialEq)]
pub struct Asf {
    /// `:version`.
    pub version: Option<String>,
    /// `:name`.
    pub name: Option<String>,
    /// `:units`.
    pub units: AsfUnits,
    /// `:documentation` text.
    pub documentation: String,
    /// `:root`.
    pub root: AsfRoot,
    /// Bones in `:bonedata` order.
    pub bones: Vec<AsfBone>,
}

impl Asf {
    /// The index of the bone named `name` (exact match).
    pub fn bone(&self, name: &str) -> Option<usize> {
        self.bones.iter().position(|b| b.name == name)
    }

    /// Bones in depth-first order from the root (children in `:hierarchy`
    /// order): the joint order of the baked motion.
    pub fn depth_first(&self) -> Vec<usize> {
        let mut out = Vec::with_capacity(self.bones.len());
        let mut stack: Vec<usize> = self.root.children.iter().rev().copied().collect();
        while let Some(b) = stack.pop() {
            out.push(b);
            stack.extend(self.bones[b].children.iter().rev());
        }
        out
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Section {
    None,
    Units,
    Documentation,
    Root,
    Bonedata,
    Hierarchy,
    Skipped,
}

/// A bone being read, with the lines of its attributes for later errors.
struct Draft {
    begin: usize,
    id: Option<i64>,
    name: Option<(String, usize, usize)>,
    direction: Option<[f64; 3]>,
    direction_at: (usize, usize),
    length: Option<f64>,
    axis: [f64; 3],
    axis_order: [usize; 3],
    dof: Vec<Dof>,
    limits: Vec<(f64, f64)>,
    /// The line and column of `limits`.
    limits_at: Option<(usize, usize)>,
    /// Whether more `(lo hi)` lines may follow (the last attribute was
    /// `limits`).
    limits_open: bool,
}

struct Parser<'a> {
    file: &'a str,
    angle: f64,
}

type Tok<'a> = (usize, &'a str);

impl<'a> Parser<'a> {
    fn err(&self, no: usize, line: &str, byte: usize, msg: impl Into<String>) -> AsfError {
        AsfError::new(self.file, no, column(line, byte), msg)
    }

    fn number(&self, no: usize, line: &str, t: Tok, what: &str) -> Result<f64, AsfError> {
        match t.1.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.err(
                no,
                line,
                t.0,
                format!("{what}: expected a finite number, found '{}'", t.1),
            )),
        }
    }

    /// `n` numbers after the keyword token `toks[0]`.
    fn numbers<const N: usize>(
        &self,
        no: usize,
        line: &str,
        toks: &[Tok],
        what: &str,
    ) -> Result<[f64; N], AsfError> {
        let mut out = [0.0; N];
        for (i, v) in out.iter_mut().enumerate() {
            let Some(&t) = toks.get(i + 1) else {
                let end = toks.last().map_or(0, |t| t.0 + t.1.len());
                return Err(self.err(
                    no,
                    line,
                    end,
                    format!("{what}: expected {N} numbers, found {}", toks.len() - 1),
                ));
            };
            *v = self.number(no, line, t, what)?;
        }
        if let Some(&t) = toks.get(N + 1) {
            return Err(self.err(
                no,
                line,
                t.0,
                format!("{what}: expected {N} numbers, found '{}' after them", t.1),
            ));
        }
        Ok(out)
    }

    fn axis_order(&self, no: usize, line: &str, t: Tok) -> Result<[usize; 3], AsfError> {
        let s = t.1.to_ascii_uppercase();
        let b = s.as_bytes();
        let ok = b.len() == 3
            && b.iter().all(|c| matches!(c, b'X' | b'Y' | b'Z'))
            && b[0] != b[1]
            && b[1] != b[2]
            && b[0] != b[2];
        if !ok {
            return Err(self.err(
                no,
                line,
                t.0,
                format!(
                    "axis order '{}': expected a permutation of XYZ (e.g. XYZ, ZYX)",
                    t.1
                ),
            ));
        }
        Ok([0, 1, 2].map(|i| usize::from(b[i] - b'X')))
    }

    fn dof_list(&self, no: usize, line: &str, toks: &[Tok]) -> Result<Vec<Dof>, AsfError> {
        let mut out: Vec<Dof> = Vec::new();
        for &t in toks {
            let d = Dof::parse(t.1).ok_or_else(|| {
                self.err(
                    no,
                    line,
                    t.0,
                    format!(
                        "unknown dof '{}' (expected rx, ry, rz, tx, ty, tz or l)",
                        t.1
                    ),
                )
            })?;
            if out.contains(&d) {
                return Err(self.err(no, line, t.0, format!("dof '{}' listed twice", t.1)));
            }
            out.push(d);
        }
        Ok(out)
    }

    /// `(lo hi)` pairs of a `limits` line or a continuation line.
    fn limit_pairs(
        &self,
        no: usize,
        line: &str,
        toks: &[Tok],
        out: &mut Vec<(f64, f64)>,
    ) -> Result<(), AsfError> {
        let mut i = 0;
        while i < toks.len() {
            let group = toks.get(i..i + 4);
            let ok = group.is_some_and(|g| g[0].1 == "(" && g[3].1 == ")");
            if !ok {
                return Err(self.err(
                    no,
                    line,
                    toks[i].0,
                    format!("limits: expected '(lo hi)', found '{}'", toks[i].1),
                ));
            }
            let g = &toks[i..i + 4];
            let mut pair = [0.0; 2];
            for (k, v) in pair.iter_mut().enumerate() {
                let t = g[k + 1];
                *v = match t.1.parse::<f64>() {
                    Ok(x) if !x.is_nan() => x,
                    _ => {
                        return Err(self.err(
                            no,
                            line,
                            t.0,
                            format!("limits: expected a number or inf, found '{}'", t.1),
                        ))
                    }
                };
            }
            if pair[0] > pair[1] {
                return Err(self.err(
                    no,
                    line,
                    g[1].0,
                    format!("limits: lower {} above upper {}", pair[0], pair[1]),
                ));
            }
            out.push((pair[0], pair[1]));
            i += 4;
        }
        Ok(())
    }

    fn finish_bone(&self, d: Draft, bones: &mut Vec<AsfBone>) -> Result<(), AsfError> {
        let missing = |what: &str| {
            AsfError::new(
                self.file,
                d.begin,
                0,
                format!(
                    "bone{} has no {what}",
                    d.name
                        .as_ref()
                        .map(|n| format!(" '{}'", n.0))
                        .or(d.id.map(|i| format!(" with id {i}")))
                        .unwrap_or_default()
                ),
            )
        };
        let (name, name_line, name_col) = d.name.clone().ok_or_else(|| missing("name"))?;
        let dir = d.direction.ok_or_else(|| missing("direction"))?;
        let length = d.length.ok_or_else(|| missing("length"))?;
        let norm = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
        if norm < 1e-12 && length != 0.0 {
            return Err(AsfError::new(
                self.file,
                d.direction_at.0,
                d.direction_at.1,
                format!("bone '{name}': direction is zero but length is {length}"),
            ));
        }
        let direction = if norm < 1e-12 {
            [0.0; 3]
        } else {
            dir.map(|v| v / norm)
        };
        if !d.limits.is_empty() && d.limits.len() != d.dof.len() {
            let (l, c) = d.limits_at.unwrap_or((d.begin, 0));
            return Err(AsfError::new(
                self.file,
                l,
                c,
                format!(
                    "bone '{name}': {} limits for {} dof",
                    d.limits.len(),
                    d.dof.len()
                ),
            ));
        }
        if bones.iter().any(|b| b.name == name) {
            return Err(AsfError::new(
                self.file,
                name_line,
                name_col,
                format!("bone '{name}' is defined twice"),
            ));
        }
        if name.eq_ignore_ascii_case("root") {
            return Err(AsfError::new(
                self.file,
                name_line,
                name_col,
                "a bone cannot be named 'root' (the name of the :root)",
            ));
        }
        // Rotational limits in degrees.
        let limits = d
            .limits
            .iter()
            .zip(&d.dof)
            .map(|(&(lo, hi), dof)| {
                if dof.is_rotation() {
                    (lo * self.angle, hi * self.angle)
                } else {
                    (lo, hi)
                }
            })
            .collect();
        bones.push(AsfBone {
            id: d.id,
            name,
            direction,
            length,
            axis: d.axis.map(|a| a * self.angle),
            axis_order: d.axis_order,
            dof: d.dof,
            limits,
            parent: None,
            children: Vec::new(),
            line: d.begin,
        });
        Ok(())
    }
}

/// Parses ASF text. `file` is only used in error messages.
pub fn parse_asf(text: &str, file: &str) -> Result<Asf, AsfError> {
    // The angle unit is needed before the bones: read `:units` first.
    let mut units = AsfUnits::default();
    let mut p = Parser { file, angle: 1.0 };
    let mut section = Section::None;
    for (no, raw) in lines(text) {
        let line = uncomment(raw);
        let toks = tokens(line, false);
        let Some(&first) = toks.first() else { continue };
        if first.1.starts_with(':') {
            section = if first.1.eq_ignore_ascii_case(":units") {
                Section::Units
            } else {
                Section::Skipped
            };
            if section != Section::Units || toks.len() == 1 {
                continue;
            }
        }
        if section != Section::Units {
            continue;
        }
        let t = if first.1.starts_with(':') {
            &toks[1..]
        } else {
            &toks[..]
        };
        let key = t[0].1.to_ascii_lowercase();
        let value = t
            .get(1)
            .ok_or_else(|| p.err(no, line, t[0].0 + t[0].1.len(), format!("{key}: no value")))?;
        match key.as_str() {
            "mass" => units.mass = p.number(no, line, *value, "mass")?,
            "length" => {
                units.length = p.number(no, line, *value, "length")?;
                if units.length <= 0.0 {
                    return Err(p.err(no, line, value.0, "length: the factor must be positive"));
                }
            }
            "angle" => {
                units.angle = match value.1.to_ascii_lowercase().as_str() {
                    "deg" | "degree" | "degrees" => AngleUnit::Deg,
                    "rad" | "radian" | "radians" => AngleUnit::Rad,
                    _ => {
                        return Err(p.err(
                            no,
                            line,
                            value.0,
                            format!("angle: expected deg or rad, found '{}'", value.1),
                        ))
                    }
                }
            }
            _ => {
                return Err(p.err(
                    no,
                    line,
                    t[0].0,
                    format!(
                        "unknown unit '{}' in :units (expected mass, length or angle)",
                        t[0].1
                    ),
                ))
            }
        }
        if let Some(extra) = t.get(2) {
            return Err(p.err(
                no,
                line,
                extra.0,
                format!("{key}: unexpected '{}' after the value", extra.1),
            ));
        }
    }
    p.angle = units.angle.degrees();

    let mut asf = Asf {
        version: None,
        name: None,
        units,
        documentation: String::new(),
        root: AsfRoot {
            order: Vec::new(),
            axis_order: [0, 1, 2],
            position: [0.0; 3],
            orientation: [0.0; 3],
            children: Vec::new(),
        },
        bones: Vec::new(),
    };
    let mut draft: Option<Draft> = None;
    let mut seen_root = false;
    let mut seen_bonedata = false;
    let mut in_hierarchy_block = false;
    let mut hierarchy_end = false;
    // (parent, child, line, column) of every `:hierarchy` link.
    let mut links: Vec<(String, String, usize, usize, usize, usize)> = Vec::new();
    section = Section::None;
    for (no, raw) in lines(text) {
        let line = uncomment(raw);
        let toks = tokens(line, section == Section::Bonedata);
        let Some(&first) = toks.first() else {
            if section == Section::Documentation {
                asf.documentation.push('\n');
            }
            continue;
        };
        if first.1.starts_with(':') {
            if let Some(d) = draft.take() {
                return Err(AsfError::new(
                    file,
                    d.begin,
                    0,
                    "bone 'begin' without 'end' before the next section",
                ));
            }
            if section == Section::Hierarchy && in_hierarchy_block {
                return Err(p.err(no, line, first.0, ":hierarchy 'begin' without 'end'"));
            }
            let kw = first.1.to_ascii_lowercase();
            let rest = line[first.0 + first.1.len()..].trim();
            section = match kw.as_str() {
                ":version" => {
                    asf.version = Some(rest.to_string());
                    Section::None
                }
                ":name" => {
                    asf.name = Some(rest.to_string());
                    Section::None
                }
                ":units" => Section::Units,
                ":documentation" => {
                    if !rest.is_empty() {
                        asf.documentation.push_str(rest);
                        asf.documentation.push('\n');
                    }
                    Section::Documentation
                }
                ":root" => {
                    seen_root = true;
                    Section::Root
                }
                ":bonedata" => {
                    seen_bonedata = true;
                    Section::Bonedata
                }
                ":hierarchy" => Section::Hierarchy,
                _ => Section::Skipped,
            };
            if section == Section::Root || section == Section::Bonedata {
                if let Some(&t) = toks.get(1) {
                    return Err(p.err(
                        no,
                        line,
                        t.0,
                        format!("unexpected '{}' after {}", t.1, first.1),
                    ));
                }
            }
            continue;
        }
        match section {
            Section::Units | Section::Skipped => {}
            Section::None => {
                return Err(p.err(
                    no,
                    line,
                    first.0,
                    format!(
                        "'{}' outside any section (sections start with ':')",
                        first.1
                    ),
                ))
            }
            Section::Documentation => {
                asf.documentation.push_str(line.trim());
                asf.documentation.push('\n');
            }
            Section::Root => {
                let key = first.1.to_ascii_lowercase();
                let r = &mut asf.root;
                match key.as_str() {
                    "order" => {
                        r.order = p.dof_list(no, line, &toks[1..])?;
                        if let Some(i) = r.order.iter().position(|d| *d == Dof::L) {
                            return Err(p.err(
                                no,
                                line,
                                toks[i + 1].0,
                                "the root has no length: 'l' is not a root dof",
                            ));
                        }
                    }
                    "axis" => {
                        let t = toks.get(1).ok_or_else(|| {
                            p.err(no, line, first.0 + first.1.len(), "axis: no order")
                        })?;
                        r.axis_order = p.axis_order(no, line, *t)?;
                    }
                    "position" => r.position = p.numbers::<3>(no, line, &toks, "position")?,
                    "orientation" => {
                        r.orientation = p
                            .numbers::<3>(no, line, &toks, "orientation")?
                            .map(|a| a * p.angle);
                    }
                    _ => {
                        return Err(p.err(
                            no,
                            line,
                            first.0,
                            format!(
                                "unknown root attribute '{}' (expected order, axis, position or orientation)",
                                first.1
                            ),
                        ))
                    }
                }
            }
            Section::Bonedata => {
                let key = first.1.to_ascii_lowercase();
                if key == "begin" {
                    if draft.is_some() {
                        return Err(p.err(
                            no,
                            line,
                            first.0,
                            "'begin' inside a bone (missing 'end')",
                        ));
                    }
                    draft = Some(Draft {
                        begin: no,
                        id: None,
                        name: None,
                        direction: None,
                        direction_at: (no, 0),
                        length: None,
                        axis: [0.0; 3],
                        axis_order: [0, 1, 2],
                        dof: Vec::new(),
                        limits: Vec::new(),
                        limits_at: None,
                        limits_open: false,
                    });
                    continue;
                }
                let Some(d) = draft.as_mut() else {
                    return Err(p.err(
                        no,
                        line,
                        first.0,
                        format!("'{}' outside a bone's begin … end", first.1),
                    ));
                };
                if first.1 == "(" {
                    if !d.limits_open {
                        return Err(p.err(no, line, first.0, "'(' outside a 'limits' list"));
                    }
                    p.limit_pairs(no, line, &toks, &mut d.limits)?;
                    continue;
                }
                d.limits_open = key == "limits";
                match key.as_str() {
                    "end" => {
                        let d = draft.take().unwrap_or_else(|| unreachable!());
                        p.finish_bone(d, &mut asf.bones)?;
                    }
                    "id" => {
                        let t = toks.get(1).ok_or_else(|| {
                            p.err(no, line, first.0 + first.1.len(), "id: no value")
                        })?;
                        d.id = Some(t.1.parse::<i64>().map_err(|_| {
                            p.err(no, line, t.0, format!("id: expected an integer, found '{}'", t.1))
                        })?);
                    }
                    "name" => {
                        let t = toks.get(1).ok_or_else(|| {
                            p.err(no, line, first.0 + first.1.len(), "name: no value")
                        })?;
                        if let Some(x) = toks.get(2) {
                            return Err(p.err(
                                no,
                                line,
                                x.0,
                                format!("name: unexpected '{}' (bone names have no spaces)", x.1),
                            ));
                        }
                        d.name = Some((t.1.to_string(), no, column(line, t.0)));
                    }
                    "direction" => {
                        d.direction = Some(p.numbers::<3>(no, line, &toks, "direction")?);
                        d.direction_at = (no, column(line, first.0));
                    }
                    "length" => {
                        let [l] = p.numbers::<1>(no, line, &toks, "length")?;
                        if l < 0.0 {
                            return Err(p.err(no, line, toks[1].0, "length: negative"));
                        }
                        d.length = Some(l);
                    }
                    "axis" => {
                        if toks.len() != 5 {
                            return Err(p.err(
                                no,
                                line,
                                first.0,
                                "axis: expected three angles and an order (e.g. 'axis 0 0 20 XYZ')",
                            ));
                        }
                        d.axis = p.numbers::<3>(no, line, &toks[..4], "axis")?;
                        d.axis_order = p.axis_order(no, line, toks[4])?;
                    }
                    "dof" => d.dof = p.dof_list(no, line, &toks[1..])?,
                    "limits" => {
                        d.limits.clear();
                        d.limits_at = Some((no, column(line, first.0)));
                        p.limit_pairs(no, line, &toks[1..], &mut d.limits)?;
                    }
                    "bodymass" | "cofmass" => {}
                    _ => {
                        return Err(p.err(
                            no,
                            line,
                            first.0,
                            format!(
                                "unknown bone attribute '{}' (expected id, name, direction, length, axis, dof, limits, bodymass, cofmass or end)",
                                first.1
                            ),
                        ))
                    }
                }
            }
            Section::Hierarchy => {
                if first.1.eq_ignore_ascii_case("begin") && toks.len() == 1 {
                    if in_hierarchy_block || hierarchy_end {
                        return Err(p.err(no, line, first.0, ":hierarchy has a second 'begin'"));
                    }
                    in_hierarchy_block = true;
                    continue;
                }
                if first.1.eq_ignore_ascii_case("end") && toks.len() == 1 {
                    if !in_hierarchy_block {
                        return Err(p.err(
                            no,
                            line,
                            first.0,
                            "'end' without 'begin' in :hierarchy",
                        ));
                    }
                    in_hierarchy_block = false;
                    hierarchy_end = true;
                    continue;
                }
                if !in_hierarchy_block {
                    return Err(p.err(
                        no,
                        line,
                        first.0,
                        format!("'{}' outside :hierarchy's begin … end", first.1),
                    ));
                }
                if toks.len() < 2 {
                    return Err(p.err(
                        no,
                        line,
                        first.0 + first.1.len(),
                        format!("'{}' names no children", first.1),
                    ));
                }
                for &c in &toks[1..] {
                    links.push((
                        first.1.to_string(),
                        c.1.to_string(),
                        no,
                        column(line, first.0),
                        no,
                        column(line, c.0),
                    ));
                }
            }
        }
    }
    if let Some(d) = draft {
        return Err(AsfError::new(
            file,
            d.begin,
            0,
            "bone 'begin' without 'end'",
        ));
    }
    if in_hierarchy_block {
        return Err(AsfError::new(
            file,
            0,
            0,
            ":hierarchy 'begin' without 'end'",
        ));
    }
    if !seen_root {
        return Err(AsfError::new(file, 0, 0, "no :root section"));
    }
    if !seen_bonedata && !links.is_empty() {
        return Err(AsfError::new(file, 0, 0, "no :bonedata section"));
    }
    link(&mut asf, &links, file)?;
    Ok(asf)
}

/// Applies the `:hierarchy` links and checks the tree: every bone has one
/// parent and hangs from the root.
fn link(
    asf: &mut Asf,
    links: &[(String, String, usize, usize, usize, usize)],
    file: &str,
) -> Result<(), AsfError> {
    let index: HashMap<String, usize> = asf
        .bones
        .iter()
        .enumerate()
        .map(|(i, b)| (b.name.clone(), i))
        .collect();
    let mut has_parent: Vec<Option<usize>> = vec![None; asf.bones.len()];
    for (parent, child, pl, pc, cl, cc) in links {
        let p = if parent == "root" {
            None
        } else {
            Some(*index.get(parent).ok_or_else(|| {
                AsfError::new(
                    file,
                    *pl,
                    *pc,
                    format!("unknown bone '{parent}' in :hierarchy (not in :bonedata)"),
                )
            })?)
        };
        if child == "root" {
            return Err(AsfError::new(file, *cl, *cc, "the root cannot be a child"));
        }
        let c = *index.get(child).ok_or_else(|| {
            AsfError::new(
                file,
                *cl,
                *cc,
                format!("unknown bone '{child}' in :hierarchy (not in :bonedata)"),
            )
        })?;
        if let Some(line) = has_parent[c] {
            return Err(AsfError::new(
                file,
                *cl,
                *cc,
                format!("bone '{child}' has a second parent (first given on line {line})"),
            ));
        }
        if p == Some(c) {
            return Err(AsfError::new(
                file,
                *cl,
                *cc,
                format!("bone '{child}' is its own parent"),
            ));
        }
        has_parent[c] = Some(*cl);
        asf.bones[c].parent = p;
        match p {
            None => asf.root.children.push(c),
            Some(p) => asf.bones[p].children.push(c),
        }
    }
    for (i, b) in asf.bones.iter().enumerate() {
        if has_parent[i].is_none() {
            return Err(AsfError::new(
                file,
                b.line,
                0,
                format!(
                    "bone '{}' is missing from the :hierarchy (no parent names it)",
                    b.name
                ),
            ));
        }
    }
    // Every bone has one parent; those not reached from the root form cycles.
    let order = asf.depth_first();
    if order.len() != asf.bones.len() {
        let mut reached = vec![false; asf.bones.len()];
        for &b in &order {
            reached[b] = true;
        }
        let first = (0..asf.bones.len())
            .find(|&b| !reached[b])
            .unwrap_or_default();
        let mut cycle = vec![asf.bones[first].name.clone()];
        let mut b = asf.bones[first].parent;
        while let Some(x) = b {
            if x == first || cycle.len() > asf.bones.len() {
                break;
            }
            cycle.push(asf.bones[x].name.clone());
            b = asf.bones[x].parent;
        }
        let line = has_parent[first].unwrap_or(0);
        return Err(AsfError::new(
            file,
            line,
            0,
            format!(
                "the :hierarchy has a cycle ({} → back), not reached from the root",
                cycle.join(" → ")
            ),
        ));
    }
    Ok(())
}
