//! STEP 2 of `gc_execute_line`: the words of a line imported into a [`Block`], with the errors GRBL raises while
//! reading them (bad letters and numbers, unsupported commands, modal group violations, repeated words).

use super::{
    AxisCommand, Block, Flow, G_ARC_DISTANCE, G_CONTROL, G_COORD, G_CUTTER, G_DISTANCE,
    G_FEED_MODE, G_MOTION, G_NONMODAL, G_PLANE, G_TLO, G_UNITS, GcState, M_COOLANT, M_SPINDLE,
    M_STOP, MAX_TOOL_NUMBER, Motion, NonModal, Spindle, W_F, W_I, W_J, W_K, W_L, W_N, W_P, W_R,
    W_S, W_T, W_X, W_Y, W_Z, read_float,
};
use crate::settings::N_AXIS;
use crate::status::Status;

impl Block {
    /// Reads every word of the line into a block whose modes start as the parser's (a jog starts in G1 G94).
    pub(super) fn import(line: &[u8], jog: bool, st: &GcState) -> Result<Block, Status> {
        let mut block = Block::new(jog, st);
        let mut pos = 0;
        while pos < line.len() {
            let letter = line[pos];
            if !letter.is_ascii_uppercase() {
                return Err(Status::ExpectedCommandLetter);
            }
            pos += 1;
            let value = read_float(line, &mut pos).ok_or(Status::BadNumberFormat)?;
            let int_value = value.trunc() as i64;
            let mantissa = ((value - int_value as f64) * 100.0).round() as i64;
            match letter {
                b'G' => block.import_g(int_value, mantissa)?,
                b'M' => block.import_m(int_value, mantissa)?,
                _ => block.import_value(letter, value)?,
            }
        }
        // Axis words without a command that takes them belong to the motion mode (start of STEP 3 in GRBL).
        if block.axis_words != 0 && block.axis_command == AxisCommand::None {
            block.axis_command = AxisCommand::MotionMode;
        }
        Ok(block)
    }

    /// The block before any word: the parser's modes, no words.
    fn new(jog: bool, st: &GcState) -> Block {
        Block {
            jog,
            motion: if jog { Motion::Linear } else { st.motion },
            inverse_time: if jog { false } else { st.inverse_time },
            inches: st.inches,
            incremental: st.incremental,
            plane: st.plane,
            coord_select: st.coord_select,
            flow: Flow::Running,
            spindle: st.spindle,
            flood: st.flood,
            mist: st.mist,
            tlo_mode: None,
            non_modal: NonModal::None,
            axis_command: AxisCommand::None,
            command_words: 0,
            value_words: 0,
            axis_words: 0,
            ijk_words: 0,
            xyz: [0.0; N_AXIS],
            ijk: [0.0; N_AXIS],
            f: 0.0,
            l: 0.0,
            n: 0.0,
            p: 0.0,
            r: 0.0,
            s: st.spindle_speed,
            t: 0.0,
            tool_length_offset: st.tool_length_offset,
            coord_system: st.coord_system,
            coord_offset: st.coord_offset,
            coord_data_write: None,
            go_home: None,
            arc: None,
        }
    }

    /// A G word: its modal group and mode.
    fn import_g(&mut self, int_value: i64, mantissa: i64) -> Result<(), Status> {
        let (group, mantissa) = match int_value {
            10 | 28 | 30 | 92 | 4 | 53 => (G_NONMODAL, self.import_non_modal(int_value, mantissa)?),
            0..=3 | 38 | 80 => (G_MOTION, self.import_motion(int_value, mantissa)?),
            17..=19 => {
                self.plane = (int_value - 17) as u8;
                (G_PLANE, mantissa)
            }
            90 | 91 => {
                if mantissa == 0 {
                    self.incremental = int_value == 91;
                    (G_DISTANCE, mantissa)
                } else {
                    if mantissa != 10 || int_value == 90 {
                        return Err(Status::UnsupportedCommand);
                    }
                    (G_ARC_DISTANCE, 0)
                }
            }
            93 | 94 => {
                self.inverse_time = int_value == 93;
                (G_FEED_MODE, mantissa)
            }
            20 | 21 => {
                self.inches = int_value == 20;
                (G_UNITS, mantissa)
            }
            40 => (G_CUTTER, mantissa),
            43 | 49 => (G_TLO, self.import_tool_length_offset(int_value, mantissa)?),
            54..=59 => {
                self.coord_select = (int_value - 54) as usize;
                (G_COORD, mantissa)
            }
            61 => {
                if mantissa != 0 {
                    return Err(Status::UnsupportedCommand);
                }
                (G_CONTROL, mantissa)
            }
            _ => return Err(Status::UnsupportedCommand),
        };
        if mantissa > 0 {
            return Err(Status::CommandValueNotInteger);
        }
        self.add_command(group)
    }

    /// G4, G10, G28(.1), G30(.1), G53, G92(.1); returns the mantissa left unread.
    fn import_non_modal(&mut self, int_value: i64, mantissa: i64) -> Result<i64, Status> {
        if matches!(int_value, 10 | 28 | 30 | 92) && mantissa == 0 {
            self.claim_axis_words(AxisCommand::NonModal)?;
        }
        self.non_modal = match (int_value, mantissa) {
            (4, _) => NonModal::Dwell,
            (10, _) => NonModal::SetCoordData,
            (53, _) => NonModal::AbsoluteOverride,
            (28, 0) => NonModal::GoHome0,
            (28, 10) => NonModal::SetHome0,
            (30, 0) => NonModal::GoHome1,
            (30, 10) => NonModal::SetHome1,
            (92, 0) => NonModal::SetCoordOffset,
            (92, 10) => NonModal::ResetCoordOffset,
            _ => return Err(Status::UnsupportedCommand),
        };
        Ok(if matches!(int_value, 28 | 30 | 92) {
            0
        } else {
            mantissa
        })
    }

    /// G0..G3, G38.2..G38.5, G80; returns the mantissa left unread.
    fn import_motion(&mut self, int_value: i64, mantissa: i64) -> Result<i64, Status> {
        if int_value != 80 {
            self.claim_axis_words(AxisCommand::MotionMode)?;
        }
        let mut mantissa = mantissa;
        self.motion = match int_value {
            0 => Motion::Seek,
            1 => Motion::Linear,
            2 => Motion::Cw,
            3 => Motion::Ccw,
            80 => Motion::None,
            _ => {
                if !matches!(mantissa, 20 | 30 | 40 | 50) {
                    return Err(Status::UnsupportedCommand);
                }
                let k = (mantissa / 10) as u8;
                mantissa = 0;
                Motion::Probe(k)
            }
        };
        Ok(mantissa)
    }

    /// G43.1 and G49; returns the mantissa left unread.
    fn import_tool_length_offset(&mut self, int_value: i64, mantissa: i64) -> Result<i64, Status> {
        self.claim_axis_words(AxisCommand::ToolLengthOffset)?;
        if int_value == 49 {
            self.tlo_mode = Some(false);
        } else if mantissa == 10 {
            self.tlo_mode = Some(true);
        } else {
            return Err(Status::UnsupportedCommand);
        }
        Ok(0)
    }

    /// Only one command of a block may take the axis words.
    fn claim_axis_words(&mut self, command: AxisCommand) -> Result<(), Status> {
        if self.axis_command != AxisCommand::None {
            return Err(Status::AxisCommandConflict);
        }
        self.axis_command = command;
        Ok(())
    }

    /// An M word: its modal group and mode.
    fn import_m(&mut self, int_value: i64, mantissa: i64) -> Result<(), Status> {
        if mantissa > 0 {
            return Err(Status::CommandValueNotInteger);
        }
        let group = match int_value {
            0 | 1 | 2 | 30 => {
                self.flow = match int_value {
                    0 => Flow::Paused,
                    1 => Flow::Running, // M1 optional stop is not supported: ignored.
                    2 => Flow::End,
                    _ => Flow::EndRewind,
                };
                M_STOP
            }
            3..=5 => {
                self.spindle = match int_value {
                    3 => Spindle::Cw,
                    4 => Spindle::Ccw,
                    _ => Spindle::Off,
                };
                M_SPINDLE
            }
            8 | 9 => {
                if int_value == 8 {
                    self.flood = true;
                } else {
                    self.flood = false;
                    self.mist = false;
                }
                M_COOLANT
            }
            _ => return Err(Status::UnsupportedCommand),
        };
        self.add_command(group)
    }

    /// One command per modal group and block.
    fn add_command(&mut self, group: u32) -> Result<(), Status> {
        if self.command_words & group != 0 {
            return Err(Status::ModalGroupViolation);
        }
        self.command_words |= group;
        Ok(())
    }

    /// A value word (F, I, J, K, L, N, P, R, S, T, X, Y, Z).
    fn import_value(&mut self, letter: u8, value: f64) -> Result<(), Status> {
        let bit = match letter {
            b'F' => {
                self.f = value;
                W_F
            }
            b'I' => {
                self.ijk[0] = value;
                self.ijk_words |= 1;
                W_I
            }
            b'J' => {
                self.ijk[1] = value;
                self.ijk_words |= 2;
                W_J
            }
            b'K' => {
                self.ijk[2] = value;
                self.ijk_words |= 4;
                W_K
            }
            b'L' => {
                self.l = value;
                W_L
            }
            b'N' => {
                self.n = value.trunc();
                W_N
            }
            b'P' => {
                self.p = value;
                W_P
            }
            b'R' => {
                self.r = value;
                W_R
            }
            b'S' => {
                self.s = value;
                W_S
            }
            b'T' => {
                if value > MAX_TOOL_NUMBER {
                    return Err(Status::MaxValueExceeded);
                }
                self.t = value;
                W_T
            }
            b'X' => {
                self.xyz[0] = value;
                self.axis_words |= 1;
                W_X
            }
            b'Y' => {
                self.xyz[1] = value;
                self.axis_words |= 2;
                W_Y
            }
            b'Z' => {
                self.xyz[2] = value;
                self.axis_words |= 4;
                W_Z
            }
            _ => return Err(Status::UnsupportedCommand),
        };
        if self.value_words & bit != 0 {
            return Err(Status::WordRepeated);
        }
        if bit & (W_F | W_N | W_P | W_T | W_S) != 0 && value < 0.0 {
            return Err(Status::NegativeValue);
        }
        self.value_words |= bit;
        Ok(())
    }
}
