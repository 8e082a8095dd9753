//! What `flatcut serve` was started on — a project, a design or a model — and what that means for
//! the workbench: the design file edits are saved to, and the project its pieces are run as.
//!
//! - A project file (`name`, `design`, `[material]`, …): its design is edited, and the pattern,
//!   nest and jobs are the project's, byte for byte what `flatcut run` writes.
//! - A design file (TOML or JSON): edited in place, and run as a project with
//!   [`DEFAULT_PROJECT`]'s settings (no material limits, a 600 × 400 mm sheet, the drag knife).
//! - A model (mesh or STEP): shown as one `[[part]]` whose surface is the model, so style lines
//!   can be drawn on it; saved as `<model>.design.toml` beside it (the model is never written).

use std::path::{Path, PathBuf};

use flatcut::design::Design;
use flatcut::project::Project;

/// The settings a design served on its own runs with: `flatcut run` on a project file holding
/// these keys and `design = "<the design>"` writes the same files.
pub const DEFAULT_PROJECT: &str = r#"name = "design"
design = "design.toml"
[material]
name = "material"
[sheet]
width_mm = 600.0
height_mm = 400.0
spacing_mm = 2.0
[machine]
profile = "knife"
"#;

/// Which kind of file the workbench was started on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum InputKind {
    /// A project file (`project.toml`) naming its design.
    Project,
    /// A design file (TOML or JSON).
    Design,
    /// A mesh or CAD model, around which a design is drawn.
    Model,
}

/// The opened input.
#[derive(Clone, Debug)]
pub struct Opened {
    /// What kind of file `input` is.
    pub kind: InputKind,
    /// The file named on the command line.
    pub input: PathBuf,
    /// The design file edits are saved to (for a model, written on the first save).
    pub design_path: PathBuf,
    /// The project the design runs as (the project file's, or the defaults).
    pub project: Project,
    /// The design's text when the workbench opens: the file's, or for a model the design drawn
    /// around it.
    pub text: String,
}

/// Why the input cannot be opened; the message names the file.
#[derive(Debug, thiserror::Error)]
pub enum OpenError {
    /// The file is missing, unreadable or of a kind the workbench does not open.
    #[error("{path}: {message}")]
    Input {
        /// The file.
        path: String,
        /// What is wrong with it.
        message: String,
    },
    /// The project file is invalid.
    #[error(transparent)]
    Project(#[from] flatcut::project::ProjectError),
    /// The design is invalid.
    #[error(transparent)]
    Design(#[from] flatcut::design::DesignError),
}

fn input_err(path: &Path, message: impl Into<String>) -> OpenError {
    OpenError::Input {
        path: path.display().to_string(),
        message: message.into(),
    }
}

/// Whether a TOML file is a project (it names a `design`) rather than a design.
fn is_project(text: &str) -> bool {
    toml::from_str::<toml::Table>(text).is_ok_and(|t| t.contains_key("design"))
}

/// Opens what `flatcut serve` was started on; without a file, `project.toml` or `design.toml`
/// in the current directory.
pub fn open(input: Option<&Path>) -> Result<Opened, OpenError> {
    let input = match input {
        Some(p) => p.to_path_buf(),
        None => ["project.toml", "design.toml"]
            .iter()
            .map(PathBuf::from)
            .find(|p| p.is_file())
            .ok_or_else(|| {
                input_err(
                    Path::new("."),
                    "no project.toml or design.toml here: name a project, design or model (flatcut serve patterns/shoe/project.toml)",
                )
            })?,
    };
    if !input.is_file() {
        return Err(input_err(&input, "no such file"));
    }
    let model = flatcut::mesh::io::is_mesh_path(&input) || flatcut::step::is_step_path(&input);
    if model {
        return open_model(&input);
    }
    let text = std::fs::read_to_string(&input).map_err(|e| input_err(&input, e.to_string()))?;
    let is_json = input
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"));
    if !is_json && is_project(&text) {
        let project = Project::load(&input)?;
        let design_path = project.design_path();
        if flatcut::mesh::io::is_mesh_path(&design_path)
            || flatcut::step::is_step_path(&design_path)
        {
            let mut m = open_model(&design_path)?;
            m.kind = InputKind::Project;
            m.input = input;
            m.project = project;
            return Ok(m);
        }
        let text = std::fs::read_to_string(&design_path)
            .map_err(|e| input_err(&design_path, e.to_string()))?;
        return Ok(Opened {
            kind: InputKind::Project,
            input,
            design_path,
            project,
            text,
        });
    }
    let project = default_project(&input)?;
    Ok(Opened {
        kind: InputKind::Design,
        design_path: input.clone(),
        input,
        project,
        text,
    })
}

/// The project a design served on its own runs as ([`DEFAULT_PROJECT`], named after the file).
pub fn default_project(design: &Path) -> Result<Project, OpenError> {
    let mut p: Project = toml::from_str(DEFAULT_PROJECT)
        .map_err(|e| input_err(design, format!("default project: {e}")))?;
    p.name = design
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "design".into());
    p.design = design
        .file_name()
        .map(PathBuf::from)
        .unwrap_or_else(|| design.to_path_buf());
    p.dir = design.parent().map(Path::to_path_buf).unwrap_or_default();
    Ok(p)
}

/// A model as a design of one part whose surface is the model, with one piece covering it.
/// When the model's design file exists (saved before), that design is opened instead.
fn open_model(model: &Path) -> Result<Opened, OpenError> {
    let saved = model_design_path(model);
    if saved.is_file() {
        let text = std::fs::read_to_string(&saved).map_err(|e| input_err(&saved, e.to_string()))?;
        return Ok(Opened {
            kind: InputKind::Model,
            input: model.to_path_buf(),
            project: default_project(&saved)?,
            design_path: saved,
            text,
        });
    }
    let design = Design::load(model)?;
    let base = model.parent().unwrap_or(Path::new("."));
    let tol = flatcut::geom::Tolerances::DEFAULT
        .with_chord_mm(flatcut::run::RunOptions::DEFAULT_CHORD_MM);
    let asm = design.assemble(base, &tol)?;
    let first = asm
        .pieces
        .first()
        .ok_or_else(|| input_err(model, "the model has no surface"))?;
    let at = first
        .mesh
        .triangles
        .first()
        .map(|t| first.mesh.positions[t[0] as usize])
        .ok_or_else(|| input_err(model, "the model has no triangles"))?;
    let file = model
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let stem = model
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "model".into());
    let kind = if flatcut::step::is_step_path(model) {
        "step"
    } else {
        "mesh"
    };
    let text = format!(
        "# Style lines drawn on {file} in the workbench (flatcut serve).\nunits = \"mm\"\n\n[[part]]\nname = {name}\n[part.surface]\ntype = \"{kind}\"\nfile = {file_q}\n\n[[part.piece]]\nname = {name}\nat = [{:.4}, {:.4}, {:.4}]\n",
        at.x,
        at.y,
        at.z,
        name = toml_edit::Value::from(stem.as_str()),
        file_q = toml_edit::Value::from(file.as_str()),
    );
    let design_path = model_design_path(model);
    let project = default_project(&design_path)?;
    Ok(Opened {
        kind: InputKind::Model,
        input: model.to_path_buf(),
        design_path,
        project,
        text,
    })
}

/// Where the design drawn on a model is saved: `<model stem>.design.toml` beside it.
pub fn model_design_path(model: &Path) -> PathBuf {
    let stem = model
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "model".into());
    model.with_file_name(format!("{stem}.design.toml"))
}
