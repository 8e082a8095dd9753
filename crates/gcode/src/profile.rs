//! Machine profiles: tool kind, speeds, work area, axis conventions and per-layer settings,
//! read from TOML with bundled defaults for a pen plotter, a drag knife and a laser.

use std::collections::BTreeMap;
use std::path::Path;

use flatcut_geom::DVec2;
use flatcut_pattern::Layer;
use serde::{Deserialize, Serialize};

/// What the machine carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ToolKind {
    /// A pen plotter: lines are drawn, the pen lifted by a servo or a Z axis.
    Pen,
    /// A drag knife: the blade trails the tool axis, corners get swivel arcs.
    Knife,
    /// A laser: power by `S`, per-layer passes, kerf and lead-ins.
    Laser,
}

/// Where machine (0, 0) sits on the sheet, seen from above with the operator at the bottom.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Corner {
    /// Origin at the sheet's lower left.
    LowerLeft,
    /// Origin at the sheet's upper left.
    UpperLeft,
    /// Origin at the sheet's lower right.
    LowerRight,
    /// Origin at the sheet's upper right.
    UpperRight,
}

/// Direction of a positive machine axis on the sheet.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AxisDir {
    /// Towards the operator's right.
    Right,
    /// Towards the operator's left.
    Left,
    /// Away from the operator.
    Up,
    /// Towards the operator.
    Down,
}

/// How a pen is lifted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PenMode {
    /// A servo on the spindle PWM: `M3 S<down>` / `M3 S<up>` followed by a `G4` dwell.
    Servo,
    /// A Z axis: `G0 Z<up>` / `G1 Z<down>`.
    Z,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
/// How a pen plotter lifts and lowers its pen (`[pen]`).
pub struct PenConfig {
    /// Servo on the spindle PWM, or a Z axis.
    pub mode: PenMode,
    #[serde(default)]
    /// Servo mode: the `S` value that lifts the pen (default 0).
    pub up_s: f64,
    #[serde(default = "PenConfig::default_down_s")]
    /// Servo mode: the `S` value that lowers the pen (default 1000).
    pub down_s: f64,
    #[serde(default = "PenConfig::default_dwell_s")]
    /// Servo mode: dwell after each move of the servo, in seconds (default 0.15).
    pub dwell_s: f64,
    #[serde(default = "PenConfig::default_z_up")]
    /// Z mode: machine Z with the pen up, mm (default 3).
    pub z_up: f64,
    #[serde(default)]
    /// Z mode: machine Z with the pen down, mm (default 0).
    pub z_down: f64,
    #[serde(default = "PenConfig::default_plunge")]
    /// Z mode: feed of the pen going down, mm/min (default 1000).
    pub plunge_mm_min: f64,
}

impl PenConfig {
    fn default_down_s() -> f64 {
        1000.0
    }
    fn default_dwell_s() -> f64 {
        0.15
    }
    fn default_z_up() -> f64 {
        3.0
    }
    fn default_plunge() -> f64 {
        1000.0
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
/// How a drag knife cuts (`[knife]`).
pub struct KnifeConfig {
    /// The blade tip trails the tool axis by this distance (mm).
    pub blade_offset_mm: f64,
    /// Direction changes larger than this (degrees) get a swivel arc around the tip.
    pub swivel_angle_deg: f64,
    /// Closed loops are cut this far past their start so the piece comes free (mm).
    pub overcut_mm: f64,
    /// Machine Z with the blade lifted (mm).
    pub z_up: f64,
    /// Machine Z with the blade through the material (mm).
    pub z_down: f64,
    /// Feed of the blade going down (mm/min).
    pub plunge_mm_min: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
/// How a laser fires (`[laser]`).
pub struct LaserConfig {
    /// The controller's `$30` (spindle max): `S` for 100 % power.
    pub s_max: f64,
    /// `M8` while the job runs, `M9` at the end.
    #[serde(default)]
    pub air_assist: bool,
}

/// How an HP-GL device keeps its receive buffer from overflowing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FlowControl {
    /// Software handshake: the device sends XOFF (0x13) when its buffer fills, XON (0x11) when
    /// it has room again.
    #[default]
    XonXoff,
    /// Hardware handshake on the RTS/CTS lines (the serial driver holds the bytes back).
    RtsCts,
}

/// An HP-GL/1 device (vinyl cutter, pen plotter) on a serial line: what its job text says
/// and how it is streamed. Coordinates are plotter units of 0.025 mm.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HpglConfig {
    /// Pen (or knife holder) selected with `SP`.
    #[serde(default = "HpglConfig::default_pen")]
    pub pen: u32,
    /// `VS`: tool-down speed in cm/s; omitted when absent.
    pub velocity_cm_s: Option<f64>,
    /// `FS`: knife force in the device's units (grams on most vinyl cutters); omitted when absent.
    pub force: Option<f64>,
    /// Flow control the device uses.
    #[serde(default)]
    pub flow_control: FlowControl,
    /// The device answers `ESC.B` (free buffer bytes) and `ESC.L` (buffer size).
    #[serde(default)]
    pub buffer_query: bool,
    /// Serial speed.
    #[serde(default = "HpglConfig::default_baud")]
    pub baud: u32,
    /// A weeding border this far around the job (mm), cut last so the waste lifts in one sheet.
    pub weed_border_mm: Option<f64>,
}

impl HpglConfig {
    fn default_pen() -> u32 {
        1
    }
    fn default_baud() -> u32 {
        9600
    }
}

/// Bridges left uncut on each closed cut so small parts stay in the sheet.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TabsConfig {
    /// Tabs per closed path, evenly spaced along it.
    pub count: u32,
    /// Length of each tab along the path (mm).
    pub width_mm: f64,
}

/// Shape of a lead-in and lead-out.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LeadKind {
    /// A straight approach along the start vertex's normal.
    Line,
    /// A quarter circle tangent to the first (last) segment.
    Arc,
}

/// Where a closed cut starts and ends: off the part, in the scrap (outside an outer contour,
/// inside a hole), so a laser's pierce and a knife's entry do not mark the part.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LeadConfig {
    /// A straight lead along the normal, or a quarter-circle arc.
    pub kind: LeadKind,
    /// Length of a line lead, radius of an arc lead (mm).
    pub length_mm: f64,
}

/// Settings of one drawing layer.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LayerConfig {
    #[serde(default = "yes")]
    /// Whether the layer is run at all (default true).
    pub enabled: bool,
    /// Feed for this layer; the profile's `feed_mm_min` when absent.
    pub feed_mm_min: Option<f64>,
    /// Laser power in percent of `s_max`.
    pub power_pct: Option<f64>,
    /// Number of passes (lasers cutting thick material).
    #[serde(default = "one")]
    pub passes: u32,
    /// Tabs (bridges) on the closed paths of this layer.
    pub tabs: Option<TabsConfig>,
}

fn yes() -> bool {
    true
}
fn one() -> u32 {
    1
}

impl Default for LayerConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            feed_mm_min: None,
            power_pct: None,
            passes: 1,
            tabs: None,
        }
    }
}

/// A machine profile. All lengths in mm, feeds in mm/min.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Profile {
    /// The profile's name, as messages and headers carry it.
    pub name: String,
    /// What the machine carries.
    pub kind: ToolKind,
    /// Feed while working (mm/min), unless a layer sets its own.
    pub feed_mm_min: f64,
    /// Feed of travel moves with the tool up (mm/min).
    pub travel_mm_min: f64,
    /// Acceleration used for the run-time estimate (GRBL `$120`/`$121`).
    pub accel_mm_s2: f64,
    /// GRBL `$11`, used for the run-time estimate.
    pub junction_deviation_mm: f64,
    /// Machine travel in X and Y (GRBL `$130`, `$131`).
    pub work_area_mm: [f64; 2],
    /// Where machine (0, 0) sits on the sheet.
    pub origin: Corner,
    /// Which way the machine's +X runs on the sheet.
    pub x_axis: AxisDir,
    /// Which way the machine's +Y runs on the sheet.
    pub y_axis: AxisDir,
    /// Machine position of the drawing's origin.
    #[serde(default)]
    pub offset_mm: [f64; 2],
    /// Digits after the decimal point in the output.
    #[serde(default = "Profile::default_decimals")]
    pub decimals: u8,
    /// Arc fitting tolerance (0 disables arcs).
    #[serde(default = "Profile::default_arc_tol")]
    pub arc_tolerance_mm: f64,
    /// Pen settings; required when `kind` is pen.
    pub pen: Option<PenConfig>,
    /// Knife settings; required when `kind` is knife.
    pub knife: Option<KnifeConfig>,
    /// Laser settings; required when `kind` is laser.
    pub laser: Option<LaserConfig>,
    /// An HP-GL device instead of a GRBL controller (`flatcut hpgl`).
    pub hpgl: Option<HpglConfig>,
    /// Laser kerf (mm): outer contours are offset outward and holes inward by half of it, so
    /// the part measures true.
    #[serde(default)]
    pub kerf_mm: f64,
    /// Lead-in and lead-out of closed cuts.
    pub lead: Option<LeadConfig>,
    #[serde(default)]
    /// Per-layer settings, keyed by layer name (`cut`, `draw`, `engrave`); a layer not listed runs
    /// with the defaults.
    pub layers: BTreeMap<String, LayerConfig>,
    /// SVG input: LightBurn palette layer (`"00"`…`"29"`, `"T1"`, `"T2"`) → `cut`, `draw`,
    /// `engrave` or `skip`, over the default table of `flatcut_pattern::colours`.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub svg_colours: BTreeMap<String, flatcut_pattern::ColourJob>,
}

/// Finite and strictly positive.
fn positive(v: f64) -> bool {
    v.is_finite() && v > 0.0
}

/// A profile that cannot be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ProfileError {
    #[error("{path}: {source}")]
    /// The profile file could not be read.
    Io {
        /// The profile file's path.
        path: String,
        /// The operating system's reason.
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    /// The profile file is not valid TOML or does not fit the schema.
    Parse {
        /// The profile file's path.
        path: String,
        /// The parser's description, with line and column.
        message: String,
    },
    #[error("profile {profile}: {key} = {value}: {reason}")]
    /// A setting out of range or inconsistent with the others.
    Invalid {
        /// The profile's name.
        profile: String,
        /// The setting, e.g. `feed_mm_min`.
        key: &'static str,
        /// Its value as given.
        value: String,
        /// Why it cannot be used.
        reason: &'static str,
    },
    #[error(
        "unknown profile '{0}': use pen, knife, laser, vinyl, pen-hpgl or a path to a .toml file"
    )]
    /// Neither a bundled profile's name nor a path ending in `.toml`: the name given.
    Unknown(String),
}

const PEN: &str = include_str!("../profiles/pen.toml");
const KNIFE: &str = include_str!("../profiles/knife.toml");
const LASER: &str = include_str!("../profiles/laser.toml");
const VINYL: &str = include_str!("../profiles/vinyl.toml");
const PEN_HPGL: &str = include_str!("../profiles/pen-hpgl.toml");

impl Profile {
    fn default_decimals() -> u8 {
        3
    }
    fn default_arc_tol() -> f64 {
        0.01
    }

    /// The bundled pen-plotter profile.
    pub fn pen() -> Self {
        Self::from_toml(PEN, "pen.toml").expect("bundled profile parses")
    }
    /// The bundled drag-knife profile.
    pub fn knife() -> Self {
        Self::from_toml(KNIFE, "knife.toml").expect("bundled profile parses")
    }
    /// The bundled laser profile.
    pub fn laser() -> Self {
        Self::from_toml(LASER, "laser.toml").expect("bundled profile parses")
    }

    /// The bundled HP-GL vinyl cutter (drag knife) profile.
    pub fn vinyl() -> Self {
        Self::from_toml(VINYL, "vinyl.toml").expect("bundled profile parses")
    }
    /// The bundled HP-GL pen plotter profile.
    pub fn pen_hpgl() -> Self {
        Self::from_toml(PEN_HPGL, "pen-hpgl.toml").expect("bundled profile parses")
    }

    /// `pen`, `knife`, `laser`, `vinyl`, `pen-hpgl`, or a path to a TOML profile.
    pub fn resolve(name_or_path: &str) -> Result<Self, ProfileError> {
        match name_or_path {
            "pen" => Ok(Self::pen()),
            "knife" => Ok(Self::knife()),
            "laser" => Ok(Self::laser()),
            "vinyl" => Ok(Self::vinyl()),
            "pen-hpgl" => Ok(Self::pen_hpgl()),
            p if p.ends_with(".toml") => Self::load(Path::new(p)),
            other => Err(ProfileError::Unknown(other.to_string())),
        }
    }

    /// Reads and checks a profile file (TOML).
    pub fn load(path: &Path) -> Result<Self, ProfileError> {
        let text = std::fs::read_to_string(path).map_err(|source| ProfileError::Io {
            path: path.display().to_string(),
            source,
        })?;
        Self::from_toml(&text, &path.display().to_string())
    }

    /// Parses and validates a profile; `origin` names the source in messages.
    pub fn from_toml(text: &str, origin: &str) -> Result<Self, ProfileError> {
        let p: Profile = toml::from_str(text).map_err(|e| ProfileError::Parse {
            path: origin.to_string(),
            message: e.to_string(),
        })?;
        p.validate()?;
        Ok(p)
    }

    fn invalid(&self, key: &'static str, value: f64, reason: &'static str) -> ProfileError {
        ProfileError::Invalid {
            profile: self.name.clone(),
            key,
            value: format!("{value}"),
            reason,
        }
    }

    /// The colour → layer table for SVG input (the default with this profile's `[svg_colours]`).
    pub fn colour_table(&self) -> Result<flatcut_pattern::ColourTable, ProfileError> {
        flatcut_pattern::ColourTable::with_overrides(&self.svg_colours).map_err(|message| {
            ProfileError::Parse {
                path: self.name.clone(),
                message,
            }
        })
    }

    /// Checks ranges and that the tool section matches the kind.
    pub fn validate(&self) -> Result<(), ProfileError> {
        self.colour_table()?;
        self.validate_motion()?;
        self.validate_hpgl()?;
        self.validate_tool()?;
        self.validate_layers()
    }

    /// Feeds, acceleration, work area, number format, axes, kerf and leads.
    fn validate_motion(&self) -> Result<(), ProfileError> {
        if !positive(self.feed_mm_min) {
            return Err(self.invalid("feed_mm_min", self.feed_mm_min, "must be > 0"));
        }
        if !positive(self.travel_mm_min) {
            return Err(self.invalid("travel_mm_min", self.travel_mm_min, "must be > 0"));
        }
        if !positive(self.accel_mm_s2) {
            return Err(self.invalid("accel_mm_s2", self.accel_mm_s2, "must be > 0"));
        }
        if !(self.junction_deviation_mm.is_finite() && self.junction_deviation_mm >= 0.0) {
            return Err(self.invalid(
                "junction_deviation_mm",
                self.junction_deviation_mm,
                "must be >= 0",
            ));
        }
        for v in self.work_area_mm {
            if !positive(v) {
                return Err(self.invalid("work_area_mm", v, "must be > 0"));
            }
        }
        if self.decimals > 5 || self.decimals < 2 {
            return Err(self.invalid(
                "decimals",
                self.decimals as f64,
                "must be 2..=5 (GRBL parses at most ~8 significant digits)",
            ));
        }
        if !(self.arc_tolerance_mm.is_finite() && self.arc_tolerance_mm >= 0.0) {
            return Err(self.invalid("arc_tolerance_mm", self.arc_tolerance_mm, "must be >= 0"));
        }
        let horizontal = |a: AxisDir| matches!(a, AxisDir::Left | AxisDir::Right);
        if horizontal(self.x_axis) == horizontal(self.y_axis) {
            return Err(ProfileError::Invalid {
                profile: self.name.clone(),
                key: "x_axis/y_axis",
                value: format!("{:?}/{:?}", self.x_axis, self.y_axis),
                reason: "one axis must be horizontal and the other vertical",
            });
        }
        if !(self.kerf_mm.is_finite() && (0.0..2.0).contains(&self.kerf_mm)) {
            return Err(self.invalid("kerf_mm", self.kerf_mm, "must be in [0, 2)"));
        }
        if let Some(l) = &self.lead
            && !(l.length_mm.is_finite() && l.length_mm > 0.0 && l.length_mm <= 50.0)
        {
            return Err(self.invalid("lead.length_mm", l.length_mm, "must be in (0, 50]"));
        }
        Ok(())
    }

    /// The `[hpgl]` section, when there is one.
    fn validate_hpgl(&self) -> Result<(), ProfileError> {
        let Some(h) = &self.hpgl else {
            return Ok(());
        };
        for (key, v) in [
            ("hpgl.velocity_cm_s", h.velocity_cm_s),
            ("hpgl.force", h.force),
        ] {
            if let Some(v) = v
                && !(v.is_finite() && v > 0.0 && v < 10_000.0)
            {
                return Err(self.invalid(key, v, "must be in (0, 10000)"));
            }
        }
        if let Some(w) = h.weed_border_mm
            && !(w.is_finite() && w > 0.0)
        {
            return Err(self.invalid("hpgl.weed_border_mm", w, "must be > 0"));
        }
        if h.pen > 8 {
            return Err(self.invalid("hpgl.pen", h.pen as f64, "must be 0..=8"));
        }
        if h.baud == 0 {
            return Err(self.invalid("hpgl.baud", 0.0, "must be > 0"));
        }
        Ok(())
    }

    /// The tool section the kind needs (`[pen]`, `[knife]` or `[laser]`) and its ranges.
    fn validate_tool(&self) -> Result<(), ProfileError> {
        match self.kind {
            ToolKind::Pen if self.pen.is_none() && self.hpgl.is_none() => {
                return Err(ProfileError::Invalid {
                    profile: self.name.clone(),
                    key: "pen",
                    value: "missing".into(),
                    reason: "a pen profile needs a [pen] section",
                });
            }
            ToolKind::Knife => {
                let Some(k) = &self.knife else {
                    return Err(ProfileError::Invalid {
                        profile: self.name.clone(),
                        key: "knife",
                        value: "missing".into(),
                        reason: "a knife profile needs a [knife] section",
                    });
                };
                if !(k.blade_offset_mm.is_finite()
                    && k.blade_offset_mm >= 0.0
                    && k.blade_offset_mm < 5.0)
                {
                    return Err(self.invalid(
                        "knife.blade_offset_mm",
                        k.blade_offset_mm,
                        "must be in [0, 5)",
                    ));
                }
                if !(k.overcut_mm.is_finite() && k.overcut_mm >= 0.0) {
                    return Err(self.invalid("knife.overcut_mm", k.overcut_mm, "must be >= 0"));
                }
                if k.z_down.partial_cmp(&k.z_up) != Some(std::cmp::Ordering::Less) {
                    return Err(self.invalid("knife.z_down", k.z_down, "must be below z_up"));
                }
            }
            ToolKind::Laser => {
                let Some(l) = &self.laser else {
                    return Err(ProfileError::Invalid {
                        profile: self.name.clone(),
                        key: "laser",
                        value: "missing".into(),
                        reason: "a laser profile needs a [laser] section",
                    });
                };
                if !positive(l.s_max) {
                    return Err(self.invalid(
                        "laser.s_max",
                        l.s_max,
                        "must be > 0 (the controller's $30)",
                    ));
                }
            }
            _ => {}
        }
        Ok(())
    }

    /// The per-layer settings: known layer names, feeds, power, tabs and passes.
    fn validate_layers(&self) -> Result<(), ProfileError> {
        for (name, l) in &self.layers {
            if !["engrave", "draw", "cut"].contains(&name.as_str()) {
                return Err(ProfileError::Invalid {
                    profile: self.name.clone(),
                    key: "layers",
                    value: name.clone(),
                    reason: "layers are engrave, draw and cut",
                });
            }
            if let Some(f) = l.feed_mm_min
                && !positive(f)
            {
                return Err(self.invalid("layers.*.feed_mm_min", f, "must be > 0"));
            }
            if let Some(p) = l.power_pct
                && !(p.is_finite() && (0.0..=100.0).contains(&p))
            {
                return Err(self.invalid("layers.*.power_pct", p, "must be in [0, 100]"));
            }
            if let Some(t) = &l.tabs
                && !(t.count <= 64 && t.width_mm.is_finite() && t.width_mm > 0.0)
            {
                return Err(self.invalid(
                    "layers.*.tabs",
                    t.width_mm,
                    "count <= 64 and width_mm > 0",
                ));
            }
            if l.passes == 0 || l.passes > 50 {
                return Err(self.invalid("layers.*.passes", l.passes as f64, "must be 1..=50"));
            }
        }
        Ok(())
    }
    /// The settings of a layer (defaults when the profile does not mention it).
    pub fn layer(&self, layer: Layer) -> LayerConfig {
        self.layers.get(layer.name()).cloned().unwrap_or_default()
    }

    /// Feed of a layer in mm/min.
    pub fn layer_feed(&self, layer: Layer) -> f64 {
        self.layer(layer).feed_mm_min.unwrap_or(self.feed_mm_min)
    }

    /// Maps a drawing point (mm, x right, y up, drawing origin) to machine coordinates.
    pub fn to_machine(&self, p: DVec2) -> DVec2 {
        let sheet = |a: AxisDir, p: DVec2| match a {
            AxisDir::Right => p.x,
            AxisDir::Left => -p.x,
            AxisDir::Up => p.y,
            AxisDir::Down => -p.y,
        };
        DVec2::new(
            self.offset_mm[0] + sheet(self.x_axis, p),
            self.offset_mm[1] + sheet(self.y_axis, p),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bundled_profiles_parse_and_validate() {
        assert_eq!(Profile::pen().kind, ToolKind::Pen);
        assert_eq!(Profile::knife().kind, ToolKind::Knife);
        assert_eq!(Profile::laser().kind, ToolKind::Laser);
        assert_eq!(Profile::laser().layer(Layer::Cut).passes, 2);
    }

    #[test]
    fn bad_profiles_name_the_key() {
        let text = PEN.replace("feed_mm_min = 3000.0\ntravel", "feed_mm_min = -1.0\ntravel");
        let e = Profile::from_toml(&text, "x.toml").unwrap_err().to_string();
        assert!(e.contains("feed_mm_min"), "{e}");
        let e = Profile::from_toml(
            &PEN.replace("y_axis = \"up\"", "y_axis = \"right\""),
            "x.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("horizontal"), "{e}");
        let e = Profile::from_toml("name = 1", "y.toml")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("y.toml"), "{e}");
        assert!(matches!(
            Profile::resolve("plasma"),
            Err(ProfileError::Unknown(_))
        ));
    }

    #[test]
    fn axis_directions_are_explicit() {
        let mut p = Profile::pen();
        assert_eq!(p.to_machine(DVec2::new(3.0, 4.0)), DVec2::new(3.0, 4.0));
        p.y_axis = AxisDir::Down;
        p.offset_mm = [0.0, 300.0];
        assert_eq!(p.to_machine(DVec2::new(3.0, 4.0)), DVec2::new(3.0, 296.0));
        p.x_axis = AxisDir::Up;
        p.y_axis = AxisDir::Right;
        p.offset_mm = [0.0, 0.0];
        assert_eq!(p.to_machine(DVec2::new(3.0, 4.0)), DVec2::new(4.0, 3.0));
    }
}
