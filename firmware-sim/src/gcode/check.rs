//! STEP 3 of `gc_execute_line`: the error checks of an imported [`Block`], one group after another in GRBL's
//! order (so a line with several errors reports the one GRBL reports), turning its words into machine millimetres.

use super::{
    ARC_RADIUS_MAX_ERROR_MM, ARC_RADIUS_REL_ERROR, ARC_RADIUS_SLACK_MM, AxisCommand, Block,
    G_COORD, G_DISTANCE, G_NONMODAL, G_UNITS, GcState, MAX_LINE_NUMBER, MM_PER_INCH, Motion,
    NonModal, Persist, W_F, W_I, W_J, W_K, W_L, W_N, W_P, W_R, W_S, W_T, W_X, W_Y, W_Z, plane_axes,
};
use crate::settings::N_AXIS;
use crate::status::Status;

impl Block {
    /// N is at most `MAX_LINE_NUMBER`.
    pub(super) fn check_line_number(&self) -> Result<(), Status> {
        if self.value_words & W_N != 0 && self.n > MAX_LINE_NUMBER {
            return Err(Status::InvalidLineNumber);
        }
        Ok(())
    }

    /// The feed of the block in its feed rate mode (a jog and G93 need their own F; G94 keeps the modal one),
    /// and F and the axis words from inches to millimetres under G20.
    pub(super) fn check_feed_and_units(&mut self, st: &GcState) -> Result<(), Status> {
        if self.jog {
            if self.value_words & W_F == 0 {
                return Err(Status::UndefinedFeedRate);
            }
            if self.inches {
                self.f *= MM_PER_INCH;
            }
        } else if self.inverse_time {
            if self.axis_command == AxisCommand::MotionMode
                && !matches!(self.motion, Motion::None | Motion::Seek)
                && self.value_words & W_F == 0
            {
                return Err(Status::UndefinedFeedRate);
            }
        } else if !st.inverse_time {
            if self.value_words & W_F != 0 {
                if self.inches {
                    self.f *= MM_PER_INCH;
                }
            } else {
                self.f = st.feed;
            }
        }
        // Switching from G93 to G94 takes F as given, without the inch conversion (as `gcode.c` does).
        if self.inches {
            for i in 0..N_AXIS {
                if self.axis_words & (1 << i) != 0 {
                    self.xyz[i] *= MM_PER_INCH;
                }
            }
        }
        Ok(())
    }

    /// G4 needs P.
    pub(super) fn check_dwell(&mut self) -> Result<(), Status> {
        if self.non_modal == NonModal::Dwell {
            if self.value_words & W_P == 0 {
                return Err(Status::ValueWordMissing);
            }
            self.value_words &= !W_P;
        }
        Ok(())
    }

    /// G43.1 takes a Z word and nothing else; G49 cancels the offset.
    pub(super) fn check_tool_length_offset(&mut self) -> Result<(), Status> {
        if self.axis_command == AxisCommand::ToolLengthOffset {
            match self.tlo_mode {
                Some(true) => {
                    if self.axis_words ^ 4 != 0 {
                        return Err(Status::G43DynamicAxisError);
                    }
                    self.tool_length_offset = self.xyz[2];
                }
                _ => self.tool_length_offset = 0.0,
            }
        } else if self.tlo_mode == Some(false) {
            self.tool_length_offset = 0.0;
        }
        Ok(())
    }

    /// G54..G59 in the block load that system's data for the block's targets.
    pub(super) fn select_coordinate_system(&mut self, persist: &Persist) {
        if self.command_words & G_COORD != 0 {
            self.coord_system = persist.coord[self.coord_select];
        }
    }

    /// G10, G92 and G92.1 take their axis words as data; every other block turns them into the machine target,
    /// then G28/G30 pick their stored position and G53 its motion mode.
    pub(super) fn check_non_modal(
        &mut self,
        st: &GcState,
        persist: &Persist,
    ) -> Result<(), Status> {
        match self.non_modal {
            NonModal::SetCoordData => self.check_coord_data(st, persist),
            NonModal::SetCoordOffset => {
                self.set_coord_offset(st);
                Ok(())
            }
            NonModal::ResetCoordOffset => {
                self.coord_offset = [0.0; N_AXIS];
                Ok(())
            }
            _ => {
                self.resolve_target(st);
                self.check_home_and_absolute_override(persist)
            }
        }
    }

    /// G10 L2/L20 P0..P6: the work offset record it writes.
    fn check_coord_data(&mut self, st: &GcState, persist: &Persist) -> Result<(), Status> {
        if self.axis_words == 0 {
            return Err(Status::NoAxisWords);
        }
        if self.value_words & (W_P | W_L) == 0 {
            return Err(Status::ValueWordMissing);
        }
        let p_int = self.p.trunc() as usize;
        if p_int > 6 {
            return Err(Status::UnsupportedCoordSys);
        }
        let lv = self.l.trunc() as i64;
        if lv != 20 {
            if lv == 2 {
                if self.value_words & W_R != 0 {
                    return Err(Status::UnsupportedCommand);
                }
            } else {
                return Err(Status::UnsupportedCommand);
            }
        }
        self.value_words &= !(W_L | W_P);
        let idx = if p_int > 0 {
            p_int - 1
        } else {
            self.coord_select
        };
        let mut data = persist.coord[idx];
        for i in 0..N_AXIS {
            if self.axis_words & (1 << i) != 0 {
                if lv == 20 {
                    data[i] = st.position[i] - self.coord_offset[i] - self.xyz[i];
                    if i == 2 {
                        data[i] -= self.tool_length_offset;
                    }
                } else {
                    data[i] = self.xyz[i];
                }
            }
        }
        self.coord_data_write = Some((idx, data));
        Ok(())
    }

    /// G92: the offset that makes the current position read as the given axis words.
    fn set_coord_offset(&mut self, st: &GcState) {
        for i in 0..N_AXIS {
            if self.axis_words & (1 << i) != 0 {
                self.coord_offset[i] = st.position[i] - self.coord_system[i] - self.xyz[i];
                if i == 2 {
                    self.coord_offset[i] -= self.tool_length_offset;
                }
            }
        }
    }

    /// The axis words as a machine target: missing axes stay, G91 adds the position, G90 the work offsets
    /// (G53 none).
    fn resolve_target(&mut self, st: &GcState) {
        if self.axis_command == AxisCommand::ToolLengthOffset || self.axis_words == 0 {
            return;
        }
        for i in 0..N_AXIS {
            if self.axis_words & (1 << i) == 0 {
                self.xyz[i] = st.position[i];
            } else if self.non_modal != NonModal::AbsoluteOverride {
                if self.incremental {
                    self.xyz[i] += st.position[i];
                } else {
                    self.xyz[i] += self.coord_system[i] + self.coord_offset[i];
                    if i == 2 {
                        self.xyz[i] += self.tool_length_offset;
                    }
                }
            }
        }
    }

    /// G28/G30 go to their stored position (via the axis words, if any); G53 works with G0 and G1 only.
    fn check_home_and_absolute_override(&mut self, persist: &Persist) -> Result<(), Status> {
        match self.non_modal {
            NonModal::GoHome0 | NonModal::GoHome1 => {
                self.go_home = Some(if self.non_modal == NonModal::GoHome0 {
                    persist.g28
                } else {
                    persist.g30
                });
                if self.axis_words == 0 {
                    self.axis_command = AxisCommand::None;
                }
            }
            NonModal::AbsoluteOverride if !matches!(self.motion, Motion::Seek | Motion::Linear) => {
                return Err(Status::G53InvalidMotionMode);
            }
            _ => {}
        }
        Ok(())
    }

    /// The motion mode with its words: G80 takes no axis words, feed motions need a feed, arcs and probes a
    /// target that is not the position.
    pub(super) fn check_motion(&mut self, st: &GcState) -> Result<(), Status> {
        if self.motion == Motion::None {
            if self.axis_words != 0 {
                return Err(Status::AxisWordsExist);
            }
        } else if self.axis_command == AxisCommand::MotionMode {
            if self.motion == Motion::Seek {
                if self.axis_words == 0 {
                    self.axis_command = AxisCommand::None;
                }
            } else {
                if self.f == 0.0 {
                    return Err(Status::UndefinedFeedRate);
                }
                match self.motion {
                    Motion::Linear if self.axis_words == 0 => {
                        self.axis_command = AxisCommand::None;
                    }
                    Motion::Cw | Motion::Ccw => self.check_arc(st)?,
                    Motion::Probe(_) if st.position == self.xyz => {
                        return Err(Status::InvalidTarget);
                    }
                    _ => {}
                }
            }
        }
        Ok(())
    }

    /// G2/G3: an end point in the plane and a centre, from R or from I/J/K.
    fn check_arc(&mut self, st: &GcState) -> Result<(), Status> {
        let (axis_0, axis_1, _) = plane_axes(self.plane);
        if self.axis_words == 0 {
            return Err(Status::NoAxisWords);
        }
        if self.axis_words & ((1 << axis_0) | (1 << axis_1)) == 0 {
            return Err(Status::NoAxisWordsInPlane);
        }
        let x = self.xyz[axis_0] - st.position[axis_0];
        let y = self.xyz[axis_1] - st.position[axis_1];
        let radius = if self.value_words & W_R != 0 {
            self.arc_centre_from_radius(st, x, y)?
        } else {
            self.arc_centre_from_offsets(x, y)?
        };
        self.arc = Some((self.ijk, radius, self.motion == Motion::Cw));
        Ok(())
    }

    /// Radius form: the centre on the side R's sign asks for; returns the radius, mm. (`x`, `y`) is the end
    /// point relative to the position in the plane.
    fn arc_centre_from_radius(&mut self, st: &GcState, x: f64, y: f64) -> Result<f64, Status> {
        let (axis_0, axis_1, _) = plane_axes(self.plane);
        self.value_words &= !W_R;
        if st.position == self.xyz {
            return Err(Status::InvalidTarget);
        }
        let mut r = self.r;
        if self.inches {
            r *= MM_PER_INCH;
        }
        let mut h = 4.0 * r * r - x * x - y * y;
        if h < 0.0 {
            return Err(Status::ArcRadiusError);
        }
        h = -h.sqrt() / x.hypot(y);
        if self.motion == Motion::Ccw {
            h = -h;
        }
        if r < 0.0 {
            h = -h;
            r = -r;
        }
        self.ijk[axis_0] = 0.5 * (x - y * h);
        self.ijk[axis_1] = 0.5 * (y + x * h);
        Ok(r)
    }

    /// Centre-offset form: the end point must lie on the circle within GRBL's tolerance; returns the radius, mm.
    fn arc_centre_from_offsets(&mut self, x: f64, y: f64) -> Result<f64, Status> {
        let (axis_0, axis_1, _) = plane_axes(self.plane);
        if self.ijk_words & ((1 << axis_0) | (1 << axis_1)) == 0 {
            return Err(Status::NoOffsetsInPlane);
        }
        self.value_words &= !(W_I | W_J | W_K);
        if self.inches {
            for v in &mut self.ijk {
                *v *= MM_PER_INCH;
            }
        }
        let x = x - self.ijk[axis_0];
        let y = y - self.ijk[axis_1];
        let target_r = x.hypot(y);
        let radius = self.ijk[axis_0].hypot(self.ijk[axis_1]);
        let delta_r = (target_r - radius).abs();
        if delta_r > ARC_RADIUS_SLACK_MM
            && (delta_r > ARC_RADIUS_MAX_ERROR_MM || delta_r > ARC_RADIUS_REL_ERROR * radius)
        {
            return Err(Status::InvalidTarget);
        }
        Ok(radius)
    }

    /// Every value word must have been used.
    pub(super) fn check_unused_words(&mut self) -> Result<(), Status> {
        self.value_words &= !(W_N | W_F | W_S | W_T);
        if self.axis_command != AxisCommand::None {
            self.value_words &= !(W_X | W_Y | W_Z);
        }
        if self.value_words != 0 {
            return Err(Status::UnusedWords);
        }
        Ok(())
    }

    /// A jog takes G20/G21, G90/G91 and G53 only.
    pub(super) fn check_jog(&self) -> Result<(), Status> {
        if self.jog {
            if self.command_words & !(G_DISTANCE | G_UNITS | G_NONMODAL) != 0 {
                return Err(Status::InvalidJogCommand);
            }
            if !matches!(self.non_modal, NonModal::None | NonModal::AbsoluteOverride) {
                return Err(Status::InvalidJogCommand);
            }
        }
        Ok(())
    }
}
