//! HP-GL plotters in the device panel: the embedded HP-GL plotter's id ([`PLOTTER_SIM`]), the
//! profile a plotter is opened with (its `[hpgl]` section: flow control, buffer queries, baud:
//! [`plotter_link`]) and the plotter as the panel shows it.

use flatcut::gcode::{FlowControl, Profile};
use flatcut_device::PlotterLink;
use flatcut_device::grbl::hpgl::HpglFlow;
use serde_json::{Value as Json, json};

/// The device id of the embedded HP-GL plotter simulator in the API.
pub const PLOTTER_SIM: &str = "plotter-sim";

/// The profile a plotter is opened with when the request names none: the project's when it has
/// an `[hpgl]` section, else `vinyl` (as `GET /api/job.plt` chooses).
pub fn default_profile(project: &Profile) -> Result<Profile, String> {
    if project.hpgl.is_some() {
        Ok(project.clone())
    } else {
        Profile::resolve("vinyl").map_err(|e| e.to_string())
    }
}

/// The link a profile's `[hpgl]` section describes: flow control, buffer queries, baud rate.
pub fn plotter_link(profile: &Profile) -> Result<PlotterLink, String> {
    let h = profile.hpgl.as_ref().ok_or_else(|| {
        format!(
            "profile {} has no [hpgl] section: use vinyl, pen-hpgl or a profile with one",
            profile.name
        )
    })?;
    Ok(PlotterLink {
        flow: match h.flow_control {
            FlowControl::XonXoff => HpglFlow::XonXoff,
            FlowControl::RtsCts => HpglFlow::RtsCts,
        },
        buffer_query: h.buffer_query,
        baud: h.baud,
    })
}

/// A plotter opened in the panel: the profile its jobs are written for, its link.
#[derive(Clone, Debug, PartialEq)]
pub struct PlotterChoice {
    /// The profile (its `[hpgl]` section writes the jobs and sets the link).
    pub profile: Profile,
    /// How it was named: `vinyl`, `pen-hpgl`, a profile file; what `GET /api/job.plt?profile=`
    /// takes.
    pub spec: String,
    /// Flow control, buffer queries, baud rate (the profile's, the baud perhaps the request's).
    pub link: PlotterLink,
}

impl PlotterChoice {
    /// The plotter `spec` names (`None`: [`default_profile`]), at `baud` if given.
    pub fn new(
        spec: Option<&str>,
        project: &Profile,
        baud: Option<u32>,
    ) -> Result<PlotterChoice, String> {
        let profile = match spec {
            Some(s) => Profile::resolve(s).map_err(|e| e.to_string())?,
            None => default_profile(project)?,
        };
        let mut link = plotter_link(&profile)?;
        if let Some(b) = baud {
            link.baud = b;
        }
        Ok(PlotterChoice {
            spec: spec.map_or_else(|| profile.name.clone(), str::to_string),
            profile,
            link,
        })
    }

    /// The plotter as `/api/devices` and the `device` event give it.
    pub fn view(&self) -> Json {
        json!({
            "profile": self.profile.name,
            "profile_spec": self.spec,
            "flow_control": match self.link.flow {
                HpglFlow::XonXoff => "xon-xoff",
                HpglFlow::RtsCts => "rts-cts",
            },
            "buffer_query": self.link.buffer_query,
            "baud": self.link.baud,
        })
    }
}
