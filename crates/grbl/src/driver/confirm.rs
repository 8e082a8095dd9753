//! Questions only the operator can answer: the sender states what it knows and what it needs
//! ([`Question`]), and whoever drives it (a terminal prompt, a GUI, a test) answers through an
//! [`Operator`] in [`super::SendOptions::operator`]. Without one, the sender refuses, as it does
//! when nobody is there.

use crate::job_edit::JobChanges;
use std::fmt;
use std::sync::Arc;

/// Something a send needs the operator to confirm before it moves the machine.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Question {
    /// Resume on a controller whose position is lost and which does not home.
    Origin(OriginQuestion),
    /// Resume a job file edited after its journal was written.
    ChangedJob(Box<JobChanges>),
}

/// Why a resume needs the operator's word on the work origin, and what the journal says.
#[derive(Debug, Clone, PartialEq)]
pub struct OriginQuestion {
    /// Why the controller's position is not known.
    pub why: String,
    /// The coordinate system the job ran in (54..=59).
    pub wcs: u8,
    /// Machine coordinates of the work origin (work zero) when the job started, as the
    /// journal recorded them; `None` in a journal that did not record them.
    pub journal_origin: Option<[f64; 3]>,
    /// Machine coordinates the controller gives the work origin now.
    pub controller_origin: [f64; 3],
    /// 1-based file line the job continues with, and the work position it starts from.
    pub resume_at: Option<(usize, [f64; 3])>,
}

fn xyz(p: [f64; 3]) -> String {
    format!("X{:.3} Y{:.3} Z{:.3}", p[0], p[1], p[2])
}

impl fmt::Display for OriginQuestion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut lines = vec![format!("The machine position is not known: {}.", self.why)];
        lines.push(match self.journal_origin {
            Some(o) => format!(
                "When the job started, its work origin (G{} zero) was at machine {} (journal).",
                self.wcs,
                xyz(o)
            ),
            None => format!(
                "The journal does not record where the work origin (G{} zero) was in machine coordinates.",
                self.wcs
            ),
        });
        lines.push(format!(
            "The controller now puts it at machine {} (a machine that does not home counts from where it powered up).",
            xyz(self.controller_origin)
        ));
        if let Some((line, p)) = self.resume_at {
            lines.push(format!(
                "The job continues with line {line}, from work position {}.",
                xyz(p)
            ));
        }
        f.write_str(&lines.join("\n"))
    }
}

impl Question {
    /// The yes/no question itself; "no" is the safe answer.
    pub fn prompt(&self) -> &'static str {
        match self {
            Question::Origin(_) => "Is the work origin where it was? [y/N] ",
            Question::ChangedJob(_) => "Resume the changed job? [y/N] ",
        }
    }
}

impl fmt::Display for Question {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Question::Origin(q) => q.fmt(f),
            Question::ChangedJob(c) => c.fmt(f),
        }
    }
}

/// The operator, as the sender sees it: answers a [`Question`] with yes (`true`) or no.
#[derive(Clone)]
pub struct Operator(Arc<dyn Fn(&Question) -> bool + Send + Sync>);

impl Operator {
    /// An operator answering with `answer`.
    pub fn new(answer: impl Fn(&Question) -> bool + Send + Sync + 'static) -> Operator {
        Operator(Arc::new(answer))
    }

    /// Asks `q`.
    pub fn confirms(&self, q: &Question) -> bool {
        (self.0)(q)
    }
}

impl fmt::Debug for Operator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("Operator(..)")
    }
}

impl PartialEq for Operator {
    fn eq(&self, other: &Operator) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}
