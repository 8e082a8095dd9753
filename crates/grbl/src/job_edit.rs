//! A job file edited after its journal was written (a bad line fixed, say): what changed, and
//! how the journal's lines map onto the edited job. The journal keeps the text of every line it
//! was written for, so the change is found by comparing the lines to send: the stretch between
//! the longest common beginning and the longest common end is what changed (several edits show
//! as one stretch from the first to the last: a summary that never hides a change). A line
//! before the stretch keeps its index; one after it moves by the difference in length; a line
//! inside it is new, and never counts as executed.

use crate::job::Job;
use crate::journal::JournalState;
use std::fmt;

/// Most changed lines shown on each side; the rest is counted.
const SHOWN: usize = 8;

/// What changed between the job a journal was written for and the job given.
#[derive(Debug, Clone, PartialEq)]
pub struct JobChanges {
    /// Lines to send in the journal's job.
    pub old_lines: usize,
    /// Lines to send in the job given.
    pub new_lines: usize,
    /// Leading lines the two have in common.
    pub prefix: usize,
    /// Trailing lines the two have in common.
    pub suffix: usize,
    /// The journal's lines in the changed stretch: (file line, text).
    pub removed: Vec<(usize, String)>,
    /// The given job's lines in the changed stretch: (file line, text).
    pub added: Vec<(usize, String)>,
    /// The last line the journal records as executed: (file line, text) in the old job.
    pub last_executed: Option<(usize, String)>,
    /// Executed lines inside the changed stretch (their old file lines): the edit changed what
    /// already ran, so only the operator can say where to continue.
    pub executed_changed: Vec<usize>,
    /// Lines the journal has in doubt (acknowledged but not confirmed, stopped part-way, or
    /// lost with the position) lie inside the changed stretch.
    pub doubt_changed: bool,
    /// The first line of the given job that the mapped journal does not count as done: (file
    /// line, text).
    pub continues_at: Option<(usize, String)>,
}

impl JobChanges {
    /// Compares the journal's job (`st`, which must hold the line texts) with `job`; `None`
    /// when the journal does not record its lines' texts.
    pub fn between(st: &JournalState, job: &Job) -> Option<JobChanges> {
        if st.texts.len() != st.lines {
            return None;
        }
        let new: Vec<&str> = job.lines.iter().map(|l| l.text.as_str()).collect();
        let old: Vec<&str> = st.texts.iter().map(|t| t.1.as_str()).collect();
        let prefix = old.iter().zip(&new).take_while(|(a, b)| a == b).count();
        let room = old.len().min(new.len()) - prefix;
        let suffix = old
            .iter()
            .rev()
            .zip(new.iter().rev())
            .take(room)
            .take_while(|(a, b)| a == b)
            .count();
        let mut c = JobChanges {
            old_lines: old.len(),
            new_lines: new.len(),
            prefix,
            suffix,
            removed: st.texts[prefix..old.len() - suffix].to_vec(),
            added: job.lines[prefix..new.len() - suffix]
                .iter()
                .map(|l| (l.source_line, l.text.clone()))
                .collect(),
            last_executed: st
                .done
                .iter()
                .rposition(|d| *d)
                .map(|i| st.texts[i].clone()),
            executed_changed: (prefix..old.len() - suffix)
                .filter(|&i| st.done[i])
                .map(|i| st.texts[i].0)
                .collect(),
            doubt_changed: false,
            continues_at: None,
        };
        let inside = |i: usize| c.map(i).is_none();
        let doubt_changed = st.unconfirmed.iter().any(|&i| inside(i))
            || st.partial.is_some_and(|(k, _)| inside(k))
            || st
                .uncertain
                .is_some_and(|(a, b)| (a..=b.min(st.lines - 1)).any(inside));
        c.doubt_changed = doubt_changed;
        let done = c.map_done(&st.done);
        c.continues_at = done
            .iter()
            .position(|d| !d)
            .map(|i| (job.lines[i].source_line, job.lines[i].text.clone()));
        Some(c)
    }

    /// Whether the journal and the job disagree where only the operator can say where to
    /// continue (`--resume-from`).
    pub fn needs_resume_line(&self) -> bool {
        self.doubt_changed || !self.executed_changed.is_empty()
    }

    /// Where the journal's line `old` is in the given job; `None` inside the changed stretch.
    pub fn map(&self, old: usize) -> Option<usize> {
        if old < self.prefix {
            Some(old)
        } else if old >= self.old_lines - self.suffix && old < self.old_lines {
            Some(old + self.new_lines - self.old_lines)
        } else {
            None
        }
    }

    /// The journal's done flags on the given job's lines (a line inside the changed stretch is
    /// not done).
    pub fn map_done(&self, done: &[bool]) -> Vec<bool> {
        let mut out = vec![false; self.new_lines];
        for (i, _) in done.iter().enumerate().filter(|(_, d)| **d) {
            if let Some(k) = self.map(i) {
                out[k] = true;
            }
        }
        out
    }
}

impl crate::journal::LineMap for JobChanges {
    fn map(&self, old: usize) -> Option<usize> {
        JobChanges::map(self, old)
    }
    fn summary(&self) -> String {
        self.to_string()
    }
}

impl fmt::Display for JobChanges {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let span = |v: &[(usize, String)]| match (v.first(), v.last()) {
            (Some(a), Some(b)) if a.0 == b.0 => format!("line {}", a.0),
            (Some(a), Some(b)) => format!("lines {}..{}", a.0, b.0),
            _ => "nothing".into(),
        };
        let mut out = vec![format!(
            "The job changed since the journal was written ({} lines to send, {} before).",
            self.new_lines, self.old_lines
        )];
        if self.removed.is_empty() && self.added.is_empty() {
            out.push(
                "The lines to send are the same; only comments, blank lines or spacing changed."
                    .into(),
            );
        } else {
            out.push(format!(
                "Changed: {} of the journal's job became {} of this file:",
                span(&self.removed),
                span(&self.added)
            ));
            for (sign, lines) in [('-', &self.removed), ('+', &self.added)] {
                for (n, t) in lines.iter().take(SHOWN) {
                    out.push(format!("  {sign} {n}: {t}"));
                }
                if lines.len() > SHOWN {
                    out.push(format!("  {sign} ... and {} more", lines.len() - SHOWN));
                }
            }
        }
        out.push(match &self.last_executed {
            Some((n, t)) => format!("Last line executed: line {n} ({t}) of the journal's job."),
            None => "No line was executed.".into(),
        });
        if self.doubt_changed {
            out.push(
                "Lines the journal has in doubt were changed: choose where to continue with --resume-from LINE."
                    .into(),
            );
        } else if !self.executed_changed.is_empty() {
            out.push(format!(
                "{} executed line(s) were changed (from line {}): choose where to continue with --resume-from LINE.",
                self.executed_changed.len(),
                self.executed_changed[0]
            ));
        } else if let Some((n, t)) = &self.continues_at {
            out.push(format!(
                "The resume continues at line {n} ({t}) of this file."
            ));
        }
        f.write_str(&out.join("\n"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::journal::Journal;

    fn journal_of(old: &str, done: &[usize]) -> (tempfile::TempDir, JournalState) {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("j.journal");
        let job = Job::parse(old).unwrap();
        let mut j = Journal::create(&p, &job).unwrap();
        for &i in done {
            j.ack(i);
        }
        if let Some(&k) = done.iter().max() {
            j.executed_through(k);
        }
        j.sync().unwrap();
        (dir, Journal::read(&p).unwrap())
    }

    #[test]
    fn an_insertion_after_the_executed_lines_maps_them_and_shifts_the_rest() {
        let old = "G1X1F100\nG1X2\nG1X3\nG1X4\n";
        let (_d, st) = journal_of(old, &[0, 1]);
        assert_eq!(st.texts[2], (3, "G1X3".to_string()));
        let new = Job::parse("G1X1F100\nG1X2\n(fix)\nG1X2.5\nG1X3\nG1X4\n").unwrap();
        let c = JobChanges::between(&st, &new).unwrap();
        assert_eq!((c.prefix, c.suffix), (2, 2));
        assert!(c.removed.is_empty());
        assert_eq!(c.added, vec![(4, "G1X2.5".to_string())]);
        assert_eq!((c.map(1), c.map(2), c.map(3)), (Some(1), Some(3), Some(4)));
        assert_eq!(c.map_done(&st.done), vec![true, true, false, false, false]);
        assert_eq!(c.continues_at, Some((4, "G1X2.5".to_string())));
        assert!(!c.needs_resume_line());
        let shown = c.to_string();
        assert!(
            shown.contains(
                "Changed: nothing of the journal's job became line 4 of this file:\n  + 4: G1X2.5"
            ),
            "{shown}"
        );
    }

    #[test]
    fn a_change_to_an_executed_line_needs_the_operators_line() {
        let (_d, st) = journal_of("G1X1F100\nG1X2\nG1X3\n", &[0, 1]);
        let new = Job::parse("G1X1F100\nG1X2.2\nG1X3\n").unwrap();
        let c = JobChanges::between(&st, &new).unwrap();
        assert_eq!(c.executed_changed, vec![2]);
        assert!(c.needs_resume_line());
        assert_eq!(c.map(1), None);
        assert!(c.to_string().contains("  - 2: G1X2\n  + 2: G1X2.2"), "{c}");
    }
}
