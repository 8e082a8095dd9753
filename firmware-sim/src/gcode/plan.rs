//! STEP 4 of `gc_execute_line`: a checked [`Block`] committed to the parser state and planned as the
//! [`Action`]s the protocol loop carries out, in GRBL's order of execution; and `mc_arc`, the chords of an arc.

use super::{
    ARC_ANGULAR_TRAVEL_EPSILON, Action, AxisCommand, Block, COORD_RECORD_BYTES, Context, Flow,
    G_COORD, GcState, LineMove, Motion, MotionCmd, NonModal, Spindle, W_T, plane_axes,
};
use crate::settings::N_AXIS;

impl Block {
    /// Commits the block and lists what the protocol loop must do for it. Nothing here fails.
    pub(super) fn plan_actions(self, ctx: &mut Context<'_>) -> Vec<Action> {
        if self.jog {
            return self.plan_jog(ctx.gc);
        }
        let mut actions = Vec::new();
        self.plan_feed_spindle_coolant(ctx.gc, ctx.settings.laser_mode, &mut actions);
        if self.non_modal == NonModal::Dwell {
            actions.push(Action::Sync);
            actions.push(Action::Dwell(self.p));
        }
        self.plan_plane_units_offsets(ctx.gc, &mut actions);
        self.plan_non_modal(ctx, &mut actions);
        self.plan_motion(ctx, &mut actions);
        self.plan_program_flow(ctx, &mut actions);
        actions
    }

    /// A jog leaves the parser modes alone (`jog_execute`); only the position follows.
    fn plan_jog(&self, gc: &mut GcState) -> Vec<Action> {
        let mut actions = Vec::new();
        if self.axis_words != 0 {
            actions.push(Action::Motion(MotionCmd {
                name: "JOG".into(),
                moves: vec![LineMove {
                    target: self.xyz,
                    rapid: false,
                    feed: self.f,
                    inverse_time: false,
                    jog: true,
                }],
                arc_center: None,
                feed: self.f,
                laser_off: true,
            }));
            gc.position = self.xyz;
        }
        actions
    }

    /// The block moves under G1/G2/G3 (the laser stays on in laser mode).
    fn motion_in_block(&self) -> bool {
        self.axis_command == AxisCommand::MotionMode
            && matches!(self.motion, Motion::Linear | Motion::Cw | Motion::Ccw)
    }

    /// Feed rate mode and F, S, T, M3/M4/M5 and M7/M8/M9; the outputs change after a sync.
    fn plan_feed_spindle_coolant(&self, gc: &mut GcState, laser: bool, actions: &mut Vec<Action>) {
        gc.inverse_time = self.inverse_time;
        gc.feed = self.f;
        // Spindle speed: a sync in GRBL unless laser mode and the block moves.
        if gc.spindle_speed != self.s {
            if gc.spindle != Spindle::Off
                && self.spindle == gc.spindle
                && !(laser && self.motion_in_block())
            {
                actions.push(Action::Sync);
                actions.push(Action::Spindle(gc.spindle, self.s));
            }
            gc.spindle_speed = self.s;
        }
        if self.value_words & W_T != 0 || self.t != 0.0 {
            gc.tool = self.t as u8;
        }
        if gc.spindle != self.spindle {
            actions.push(Action::Sync);
            actions.push(Action::Spindle(self.spindle, gc.spindle_speed));
            gc.spindle = self.spindle;
        }
        if gc.flood != self.flood || gc.mist != self.mist {
            actions.push(Action::Sync);
            actions.push(Action::Coolant(self.flood, self.mist));
            gc.flood = self.flood;
            gc.mist = self.mist;
        }
    }

    /// Plane, units, tool length offset, work coordinate system and distance mode.
    fn plan_plane_units_offsets(&self, gc: &mut GcState, actions: &mut Vec<Action>) {
        gc.plane = self.plane;
        gc.inches = self.inches;
        if (self.axis_command == AxisCommand::ToolLengthOffset || self.tlo_mode.is_some())
            && gc.tool_length_offset != self.tool_length_offset
        {
            gc.tool_length_offset = self.tool_length_offset;
            actions.push(Action::WcoChanged);
        }
        if gc.coord_select != self.coord_select
            || self.command_words & G_COORD != 0 && gc.coord_system != self.coord_system
        {
            gc.coord_select = self.coord_select;
            gc.coord_system = self.coord_system;
            actions.push(Action::WcoChanged);
        }
        gc.incremental = self.incremental;
    }

    /// G10, G28/G30 (and their .1 forms), G92/G92.1.
    fn plan_non_modal(&self, ctx: &mut Context<'_>, actions: &mut Vec<Action>) {
        let gc = &mut *ctx.gc;
        match self.non_modal {
            NonModal::SetCoordData => {
                let (idx, data) = self.coord_data_write.unwrap_or((0, [0.0; N_AXIS]));
                actions.push(Action::Sync);
                actions.push(Action::EepromWrite(COORD_RECORD_BYTES)); // EEPROM write syncs the buffer (FORCE_BUFFER_SYNC_DURING_EEPROM_WRITE)
                ctx.persist.coord[idx] = data;
                if idx == gc.coord_select {
                    gc.coord_system = data;
                    actions.push(Action::WcoChanged);
                }
            }
            NonModal::GoHome0 | NonModal::GoHome1 => {
                let name = if self.non_modal == NonModal::GoHome0 {
                    "G28"
                } else {
                    "G30"
                };
                if self.axis_command != AxisCommand::None {
                    actions.push(rapid(name, self.xyz, true));
                }
                let home = self.go_home.unwrap_or(gc.position);
                actions.push(rapid(name, home, true));
                gc.position = home;
            }
            NonModal::SetHome0 => {
                actions.push(Action::Sync);
                actions.push(Action::EepromWrite(COORD_RECORD_BYTES));
                ctx.persist.g28 = ctx.machine_position;
            }
            NonModal::SetHome1 => {
                actions.push(Action::Sync);
                actions.push(Action::EepromWrite(COORD_RECORD_BYTES));
                ctx.persist.g30 = ctx.machine_position;
            }
            NonModal::SetCoordOffset | NonModal::ResetCoordOffset => {
                gc.coord_offset = self.coord_offset;
                actions.push(Action::WcoChanged);
            }
            _ => {}
        }
    }

    /// The motion mode, and the motion when the block's axis words are for it.
    fn plan_motion(&self, ctx: &mut Context<'_>, actions: &mut Vec<Action>) {
        let gc = &mut *ctx.gc;
        gc.motion = self.motion;
        if self.motion == Motion::None || self.axis_command != AxisCommand::MotionMode {
            return;
        }
        let laser_off = ctx.settings.laser_mode && !self.motion_in_block();
        let feed = if self.inverse_time { 0.0 } else { self.f };
        match self.motion {
            Motion::Seek => actions.push(rapid("G0", self.xyz, laser_off)),
            Motion::Linear | Motion::Probe(_) => {
                actions.push(Action::Motion(MotionCmd {
                    name: self.motion.name(),
                    moves: vec![LineMove {
                        target: self.xyz,
                        rapid: false,
                        feed: self.f,
                        inverse_time: self.inverse_time,
                        jog: false,
                    }],
                    arc_center: None,
                    feed,
                    laser_off,
                }));
                if let Motion::Probe(k) = self.motion {
                    actions.push(Action::ProbeEnd(k));
                }
            }
            Motion::Cw | Motion::Ccw => {
                let (off, radius, cw) = self.arc.unwrap_or(([0.0; N_AXIS], 0.0, true));
                let (moves, center) = arc_moves(
                    gc.position,
                    self.xyz,
                    off,
                    radius,
                    plane_axes(self.plane),
                    cw,
                    ctx.settings.arc_tolerance,
                    self.f,
                    self.inverse_time,
                );
                actions.push(Action::Motion(MotionCmd {
                    name: self.motion.name(),
                    moves,
                    arc_center: Some(center),
                    feed,
                    laser_off,
                }));
            }
            Motion::None => {}
        }
        gc.position = self.xyz;
    }

    /// M0 pauses; M2/M30 end the program and reset the modes GRBL resets.
    fn plan_program_flow(&self, ctx: &mut Context<'_>, actions: &mut Vec<Action>) {
        let gc = &mut *ctx.gc;
        match self.flow {
            Flow::Paused => {
                actions.push(Action::Sync);
                actions.push(Action::Pause);
            }
            Flow::End | Flow::EndRewind => {
                actions.push(Action::Sync);
                gc.motion = Motion::Linear;
                gc.plane = 0;
                gc.incremental = false;
                gc.inverse_time = false;
                // GRBL 1.1h resets only modal groups 1, 2, 3, 5, 7, 12 and M7-M9 at program end
                // (`gcode.c`): the G92 offset, the tool length offset and F, S, T stay.
                gc.coord_select = 0;
                gc.spindle = Spindle::Off;
                gc.flood = false;
                gc.mist = false;
                if !ctx.check_mode {
                    gc.coord_system = ctx.persist.coord[0];
                    actions.push(Action::WcoChanged);
                    actions.push(Action::Spindle(Spindle::Off, 0.0));
                    actions.push(Action::Coolant(false, false));
                }
                actions.push(Action::RestoreOverrides);
                actions.push(Action::Message("Pgm End"));
            }
            Flow::Running => {}
        }
    }
}

/// One rapid move at the axis max rates (G0, the legs of G28/G30).
fn rapid(name: &str, target: [f64; N_AXIS], laser_off: bool) -> Action {
    Action::Motion(MotionCmd {
        name: name.into(),
        moves: vec![LineMove {
            target,
            rapid: true,
            feed: 0.0,
            inverse_time: false,
            jog: false,
        }],
        arc_center: None,
        feed: 0.0,
        laser_off,
    })
}

/// `mc_arc`: chords of an arc within `$12` of the true circle, ending exactly at the target.
fn arc_moves(
    position: [f64; N_AXIS],
    target: [f64; N_AXIS],
    offset: [f64; N_AXIS],
    radius: f64,
    (a0, a1, al): (usize, usize, usize),
    clockwise: bool,
    arc_tolerance: f64,
    feed: f64,
    inverse_time: bool,
) -> (Vec<LineMove>, [f64; N_AXIS]) {
    let c0 = position[a0] + offset[a0];
    let c1 = position[a1] + offset[a1];
    let mut center = position;
    center[a0] = c0;
    center[a1] = c1;
    let r0 = -offset[a0];
    let r1 = -offset[a1];
    let rt0 = target[a0] - c0;
    let rt1 = target[a1] - c1;
    let mut angular = (r0 * rt1 - r1 * rt0).atan2(r0 * rt0 + r1 * rt1);
    if clockwise {
        if angular >= -ARC_ANGULAR_TRAVEL_EPSILON {
            angular -= 2.0 * std::f64::consts::PI;
        }
    } else if angular <= ARC_ANGULAR_TRAVEL_EPSILON {
        angular += 2.0 * std::f64::consts::PI;
    }
    let tol = arc_tolerance.max(1e-6);
    let denom = (tol * (2.0 * radius - tol)).max(1e-12).sqrt();
    let segments = ((0.5 * angular * radius).abs() / denom).floor().min(1.0e6) as usize;
    let mut moves = Vec::with_capacity(segments.max(1));
    // `mc_arc` multiplies an inverse-time feed by the segment count and clears the inverse-time
    // flag: the chords run at F × segments mm/min, whatever their length.
    let (seg_feed, seg_inverse) = if inverse_time && segments > 0 {
        (feed * segments as f64, false)
    } else {
        (feed, inverse_time)
    };
    if segments > 0 {
        let theta = angular / segments as f64;
        let lin = (target[al] - position[al]) / segments as f64;
        for i in 1..segments {
            let (sn, cs) = (theta * i as f64).sin_cos();
            let mut p = position;
            p[a0] = c0 + r0 * cs - r1 * sn;
            p[a1] = c1 + r0 * sn + r1 * cs;
            p[al] = position[al] + lin * i as f64;
            moves.push(LineMove {
                target: p,
                rapid: false,
                feed: seg_feed,
                inverse_time: seg_inverse,
                jog: false,
            });
        }
    }
    moves.push(LineMove {
        target,
        rapid: false,
        feed: seg_feed,
        inverse_time: seg_inverse,
        jog: false,
    });
    (moves, center)
}
