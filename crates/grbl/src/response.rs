//! Parsing of everything GRBL 1.1h sends back: stream responses (`ok`, `error:N`), push messages
//! (`ALARM:N`, `<status>`, `[MSG:..]`, `[OPT:..]`, `$n=v`, startup echoes) and the banner.

use serde::{Deserialize, Serialize};

/// Machine state, the first field of a status report (`interface.md:512-527`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum MachineState {
    /// Nothing queued, ready.
    Idle,
    /// Executing motion.
    Run,
    /// Feed hold; `complete` is true for `Hold:0` (stopped, ready to resume) and false for `Hold:1`.
    Hold {
        /// `Hold:0`: deceleration finished.
        complete: bool,
    },
    /// Jogging.
    Jog,
    /// Alarm lock.
    Alarm,
    /// Safety door, with its sub-state 0..3.
    Door(u8),
    /// G-code check mode (`$C`).
    Check,
    /// Homing cycle.
    Home,
    /// Sleep (`$SLP`).
    Sleep,
}

impl MachineState {
    /// Parses the state field (`Idle`, `Hold:0`, `Door:2`, ...).
    pub fn parse(s: &str) -> Option<MachineState> {
        let (name, sub) = match s.split_once(':') {
            Some((n, sub)) => (n, Some(sub)),
            None => (s, None),
        };
        Some(match name {
            "Idle" => MachineState::Idle,
            "Run" => MachineState::Run,
            "Hold" => MachineState::Hold {
                complete: sub.is_none_or(|v| v == "0"),
            },
            "Jog" => MachineState::Jog,
            "Alarm" => MachineState::Alarm,
            "Door" => MachineState::Door(sub.and_then(|v| v.parse().ok()).unwrap_or(0)),
            "Check" => MachineState::Check,
            "Home" => MachineState::Home,
            "Sleep" => MachineState::Sleep,
            _ => return None,
        })
    }

    /// Short name as GRBL prints it.
    pub fn name(&self) -> String {
        match self {
            MachineState::Idle => "Idle".into(),
            MachineState::Run => "Run".into(),
            MachineState::Hold { complete } => format!("Hold:{}", if *complete { 0 } else { 1 }),
            MachineState::Jog => "Jog".into(),
            MachineState::Alarm => "Alarm".into(),
            MachineState::Door(n) => format!("Door:{n}"),
            MachineState::Check => "Check".into(),
            MachineState::Home => "Home".into(),
            MachineState::Sleep => "Sleep".into(),
        }
    }
}

/// A parsed `<...>` status report. Fields GRBL did not send are `None` (`interface.md:506`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StatusReport {
    /// Machine state.
    pub state: MachineState,
    /// Machine position, if reported as `MPos:`.
    pub mpos: Option<[f64; 3]>,
    /// Work position, if reported as `WPos:`.
    pub wpos: Option<[f64; 3]>,
    /// Work coordinate offset, sent only every 10th/30th report (`WCO:`).
    pub wco: Option<[f64; 3]>,
    /// Current feed (mm/min) and spindle speed from `FS:` or `F:`.
    pub feed: Option<f64>,
    /// Current spindle speed from `FS:`.
    pub speed: Option<f64>,
    /// `Bf:` planner blocks free and RX bytes free.
    pub buffer: Option<(u32, u32)>,
    /// `Ln:` line number (only with USE_LINE_NUMBERS).
    pub line: Option<u32>,
    /// `Ov:` feed, rapid, spindle override percentages.
    pub overrides: Option<[u32; 3]>,
    /// `Pn:` triggered input pins.
    pub pins: Option<String>,
}

impl StatusReport {
    /// Work position, derived from `MPos - WCO` when only `MPos` is reported.
    pub fn work_position(&self, last_wco: [f64; 3]) -> Option<[f64; 3]> {
        if let Some(w) = self.wpos {
            return Some(w);
        }
        let m = self.mpos?;
        let wco = self.wco.unwrap_or(last_wco);
        Some([m[0] - wco[0], m[1] - wco[1], m[2] - wco[2]])
    }

    /// Machine position, derived from `WPos + WCO` when only `WPos` is reported.
    pub fn machine_position(&self, last_wco: [f64; 3]) -> Option<[f64; 3]> {
        if let Some(m) = self.mpos {
            return Some(m);
        }
        let w = self.wpos?;
        let wco = self.wco.unwrap_or(last_wco);
        Some([w[0] + wco[0], w[1] + wco[1], w[2] + wco[2]])
    }
}

/// One line received from GRBL, classified.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum Response {
    /// `ok`: the oldest outstanding line was accepted.
    Ok,
    /// `error:N`: the oldest outstanding line was rejected; nothing in it ran.
    Error(u8),
    /// `ALARM:N` push message.
    Alarm(u8),
    /// `<...>` status report.
    Status(StatusReport),
    /// `Grbl X.Yz [...]` banner: the controller (re)started and cleared its buffers.
    Banner {
        /// Version string, e.g. `1.1h`.
        version: String,
    },
    /// `[MSG:...]` feedback message text.
    Message(String),
    /// `[OPT:codes,blocks,rx]` build options.
    Options {
        /// Option letters.
        codes: String,
        /// Planner blocks.
        blocks: u32,
        /// Serial RX buffer bytes.
        rx: u32,
    },
    /// `[VER:...]` build version.
    Version(String),
    /// `[GC:...]` parser state.
    ParserState(String),
    /// Any other `[...]` feedback (`[PRB:..]`, `[G54:..]`, `[echo:..]`, `[HLP:..]`).
    Feedback(String),
    /// `$n=value` setting line of a `$$` dump.
    Setting(u16, f64),
    /// `>line:ok` / `>line:error:N` startup-line echo (not a stream response).
    StartupLine(String),
    /// Anything else (kept verbatim so the caller can log it).
    Other(String),
}

fn parse_triple(s: &str) -> Option<[f64; 3]> {
    let mut it = s.split(',').map(|v| v.trim().parse::<f64>());
    let x = it.next()?.ok()?;
    let y = it.next()?.ok()?;
    let z = it.next().and_then(|r| r.ok()).unwrap_or(0.0);
    Some([x, y, z])
}

/// Parses a status report body (the text between `<` and `>`).
pub fn parse_status(body: &str) -> Option<StatusReport> {
    let mut fields = body.split('|');
    let state = MachineState::parse(fields.next()?)?;
    let mut r = StatusReport {
        state,
        mpos: None,
        wpos: None,
        wco: None,
        feed: None,
        speed: None,
        buffer: None,
        line: None,
        overrides: None,
        pins: None,
    };
    for f in fields {
        let Some((key, val)) = f.split_once(':') else {
            continue;
        };
        match key {
            "MPos" => r.mpos = parse_triple(val),
            "WPos" => r.wpos = parse_triple(val),
            "WCO" => r.wco = parse_triple(val),
            "FS" => {
                let mut it = val.split(',');
                r.feed = it.next().and_then(|v| v.parse().ok());
                r.speed = it.next().and_then(|v| v.parse().ok());
            }
            "F" => r.feed = val.parse().ok(),
            "Bf" => {
                let mut it = val.split(',').map(|v| v.parse::<u32>().ok());
                if let (Some(Some(a)), Some(Some(b))) = (it.next(), it.next()) {
                    r.buffer = Some((a, b));
                }
            }
            "Ln" => r.line = val.parse().ok(),
            "Ov" => {
                let v: Vec<u32> = val.split(',').filter_map(|x| x.parse().ok()).collect();
                if v.len() == 3 {
                    r.overrides = Some([v[0], v[1], v[2]]);
                }
            }
            "Pn" => r.pins = Some(val.to_string()),
            _ => {}
        }
    }
    Some(r)
}

/// Classifies one received line (without its line terminator).
pub fn parse_response(line: &str) -> Response {
    let line = line.trim_matches(|c: char| c == '\r' || c == '\n' || c == ' ' || c == '\0');
    if line == "ok" {
        return Response::Ok;
    }
    if let Some(n) = line.strip_prefix("error:")
        && let Ok(code) = n.trim().parse()
    {
        return Response::Error(code);
    }
    if let Some(n) = line.strip_prefix("ALARM:")
        && let Ok(code) = n.trim().parse()
    {
        return Response::Alarm(code);
    }
    if let Some(body) = line.strip_prefix('<').and_then(|b| b.strip_suffix('>'))
        && let Some(r) = parse_status(body)
    {
        return Response::Status(r);
    }
    if let Some(rest) = line.strip_prefix("Grbl ") {
        let version = rest.split_whitespace().next().unwrap_or("").to_string();
        return Response::Banner { version };
    }
    if let Some(body) = line.strip_prefix('[').and_then(|b| b.strip_suffix(']')) {
        if let Some(m) = body.strip_prefix("MSG:") {
            return Response::Message(m.to_string());
        }
        if let Some(o) = body.strip_prefix("OPT:") {
            let parts: Vec<&str> = o.split(',').collect();
            if parts.len() >= 3
                && let (Ok(blocks), Ok(rx)) = (parts[1].parse(), parts[2].parse())
            {
                return Response::Options {
                    codes: parts[0].to_string(),
                    blocks,
                    rx,
                };
            }
        }
        if let Some(v) = body.strip_prefix("VER:") {
            return Response::Version(v.to_string());
        }
        if let Some(g) = body.strip_prefix("GC:") {
            return Response::ParserState(g.to_string());
        }
        return Response::Feedback(body.to_string());
    }
    if let Some(rest) = line.strip_prefix('$')
        && let Some((n, v)) = rest.split_once('=')
        && let (Ok(n), Ok(v)) = (n.parse(), v.trim().parse())
    {
        return Response::Setting(n, v);
    }
    if let Some(rest) = line.strip_prefix('>') {
        return Response::StartupLine(rest.to_string());
    }
    Response::Other(line.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stream_responses() {
        assert_eq!(parse_response("ok"), Response::Ok);
        assert_eq!(parse_response("ok\r"), Response::Ok);
        assert_eq!(parse_response("error:22"), Response::Error(22));
        assert_eq!(parse_response("ALARM:3"), Response::Alarm(3));
    }

    #[test]
    fn banner_and_feedback() {
        assert_eq!(
            parse_response("Grbl 1.1h ['$' for help]"),
            Response::Banner {
                version: "1.1h".into()
            }
        );
        assert_eq!(
            parse_response("[MSG:'$H'|'$X' to unlock]"),
            Response::Message("'$H'|'$X' to unlock".into())
        );
        assert_eq!(
            parse_response("[OPT:V,15,128]"),
            Response::Options {
                codes: "V".into(),
                blocks: 15,
                rx: 128
            }
        );
        assert_eq!(
            parse_response("[VER:1.1h.20190830:]"),
            Response::Version("1.1h.20190830:".into())
        );
        assert_eq!(
            parse_response("$130=200.000"),
            Response::Setting(130, 200.0)
        );
        assert_eq!(
            parse_response(">G20G54:ok"),
            Response::StartupLine("G20G54:ok".into())
        );
        assert_eq!(
            parse_response("[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]"),
            Response::ParserState("G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0".into())
        );
    }

    #[test]
    fn status_fields_in_any_order_and_missing() {
        let Response::Status(r) = parse_response(
            "<Hold:1|MPos:1.000,-2.500,0.000|Bf:15,128|FS:157,0|WCO:0.000,1.000,0.000>",
        ) else {
            panic!("not a status report")
        };
        assert_eq!(r.state, MachineState::Hold { complete: false });
        assert_eq!(r.mpos, Some([1.0, -2.5, 0.0]));
        assert_eq!(r.buffer, Some((15, 128)));
        assert_eq!(r.feed, Some(157.0));
        assert_eq!(r.work_position([0.0; 3]), Some([1.0, -3.5, 0.0]));
        let Response::Status(r) = parse_response("<Idle|WPos:3,4,5|F:100|Ov:100,100,100|Pn:XZ>")
        else {
            panic!("not a status report")
        };
        assert_eq!(r.state, MachineState::Idle);
        assert_eq!(r.machine_position([1.0, 1.0, 1.0]), Some([4.0, 5.0, 6.0]));
        assert_eq!(r.overrides, Some([100, 100, 100]));
        assert_eq!(r.pins.as_deref(), Some("XZ"));
        assert_eq!(MachineState::parse("Door:2"), Some(MachineState::Door(2)));
        assert_eq!(MachineState::parse("Bogus"), None);
    }

    #[test]
    fn garbage_is_other() {
        assert_eq!(parse_response("<Idle"), Response::Other("<Idle".into()));
        assert_eq!(parse_response("okk"), Response::Other("okk".into()));
    }
}
