//! The run-folder layout shared with the runner, and the two study commands built on it.
//!
//! ```text
//! <run>/configurations.csv         id (or name), object, lattice, clustering, ...  (runner)
//! <run>/meshes/<id>.ply            one mesh per configuration                      (runner)
//! <run>/render/<name>.gif          one turntable per configuration, anonymous name  (render)
//! <run>/render/settings.json       the TurntableSettings every animation used       (render)
//! <run>/key.csv                    name -> configuration, kept outside render/      (render)
//! <run>/questionnaire/qNN_<a>_<b>.gif, questions.csv, questionnaire.html           (questionnaire)
//! <run>/questionnaire_key.csv      question -> configurations, outside questionnaire/
//! ```
//!
//! `render/` and `questionnaire/` hold only what participants may see: random names, numbers,
//! and settings. The keys stay one level up. Names are drawn from the seed alone and assigned in
//! manifest order, so the seed is as secret as the key: it is not written into `render/`.

use crate::animation::{decode_gif, side_by_side, DecodedGif};
use crate::names::random_names;
use crate::questionnaire::{
    plan_questions, question_file_name, questionnaire_html, Manifest, PageQuestion, Question,
    QuestionnaireOptions,
};
use crate::shade::Shading;
use crate::turntable::{Renderer, TurntableSettings};
use crate::{io_error, RenderError, Result};
use rmt_mesh::Mesh;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The manifest of a run (the runner's file, [`rmt_runfolder::layout::CONFIGURATIONS_CSV`]).
pub const CONFIGURATIONS_FILE: &str = rmt_runfolder::layout::CONFIGURATIONS_CSV;
/// Folder of the meshes, `<id>.ply` (the runner's, [`rmt_runfolder::layout::MESHES`]).
pub const MESHES_DIR: &str = rmt_runfolder::layout::MESHES;
/// Folder of the turntables.
pub const RENDER_DIR: &str = "render";
/// The settings file inside [`RENDER_DIR`].
pub const SETTINGS_FILE: &str = "settings.json";
/// Name -> configuration, in the run folder.
pub const KEY_FILE: &str = "key.csv";
/// Folder of the question animations and page.
pub const QUESTIONNAIRE_DIR: &str = "questionnaire";
/// Question -> names, inside [`QUESTIONNAIRE_DIR`].
pub const QUESTIONS_FILE: &str = "questions.csv";
/// The answer page, inside [`QUESTIONNAIRE_DIR`].
pub const HTML_FILE: &str = "questionnaire.html";
/// Question -> configurations, in the run folder.
pub const QUESTIONNAIRE_KEY_FILE: &str = "questionnaire_key.csv";

/// Reads a mesh file (binary or ASCII PLY; OBJ by extension). The one place this crate reads
/// meshes.
pub fn load_mesh(path: &Path) -> Result<Mesh> {
    Ok(rmt_mesh::io::read_mesh(path)?)
}

/// One rendered turntable.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RenderedAnimation {
    /// The anonymous name.
    pub name: String,
    /// The configuration id.
    pub id: String,
    /// The GIF file.
    pub path: PathBuf,
    /// Its size in bytes.
    pub bytes: u64,
}

/// Removes the files in `dir` whose names satisfy `stale` (output of an earlier run that the new
/// one would not overwrite).
fn remove_stale(dir: &Path, stale: impl Fn(&str) -> bool) -> Result<()> {
    for entry in std::fs::read_dir(dir).map_err(io_error(dir))? {
        let entry = entry.map_err(io_error(dir))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if stale(&name) && entry.path().is_file() {
            std::fs::remove_file(entry.path()).map_err(io_error(entry.path()))?;
        }
    }
    Ok(())
}

fn write_csv(path: &Path, header: &[&str], rows: &[Vec<String>]) -> Result<()> {
    let csv_error = |source| RenderError::Csv {
        path: path.to_path_buf(),
        source,
    };
    let mut writer = csv::Writer::from_path(path).map_err(csv_error)?;
    writer.write_record(header).map_err(csv_error)?;
    for row in rows {
        writer.write_record(row).map_err(csv_error)?;
    }
    writer.flush().map_err(io_error(path))
}

/// `experiments render`: a turntable of every configuration of the run, named with seeded random
/// names, plus `render/settings.json` and `key.csv`. `progress` is called after each animation.
///
/// Earlier `*.gif` files in `render/` are removed first, so the folder holds exactly this run's
/// animations.
///
/// **Shading per configuration.** When `configurations.csv` has a [`SHADING_COLUMN`] (the runner
/// writes one when some configuration is flat), each configuration is drawn with its own
/// shading (`smooth` or `flat`), each shading with its own palette (derived from the settings
/// with that shading, as always); `settings.json` then holds the settings with smooth shading
/// and `key.csv` says which animation is which. `settings` must then be smooth (an error
/// otherwise: the run decides). Without the column every animation takes `settings.shading`.
///
/// **Elevation per configuration.** Likewise, when `configurations.csv` has an
/// [`ELEVATION_COLUMN`] (the runner writes one when some object sets `elevation_deg`), a
/// configuration with a value there is drawn from that camera elevation, the others from
/// `settings.elevation_degrees`; `settings.json` holds `settings`.
pub fn render_run(
    run: &Path,
    settings: &TurntableSettings,
    seed: u64,
    mut progress: impl FnMut(usize, usize, &RenderedAnimation),
) -> Result<Vec<RenderedAnimation>> {
    let manifest = Manifest::read(&run.join(CONFIGURATIONS_FILE))?;
    let shadings = configuration_shadings(&manifest, &run.join(CONFIGURATIONS_FILE))?;
    if shadings.is_some() && settings.shading != Shading::Smooth {
        return Err(RenderError::InvalidSettings(format!(
            "the run's configurations set their own shading (`{SHADING_COLUMN}` column of {}): \
             render it without flat shading in the settings",
            run.join(CONFIGURATIONS_FILE).display()
        )));
    }
    let elevations = configuration_elevations(&manifest, &run.join(CONFIGURATIONS_FILE))?;
    let renderer = Renderer::new(settings.clone())?;
    // One renderer per shading and elevation the configurations ask for (the settings' own first).
    let mut renderers: Vec<Renderer> = Vec::new();
    let names = random_names(manifest.configurations.len(), seed)?;
    let render_dir = run.join(RENDER_DIR);
    std::fs::create_dir_all(&render_dir).map_err(io_error(&render_dir))?;
    remove_stale(&render_dir, |f| f.ends_with(".gif"))?;
    let key_path = run.join(KEY_FILE);
    if key_path.exists() {
        std::fs::remove_file(&key_path).map_err(io_error(&key_path))?;
    }
    let total = manifest.configurations.len();
    let mut rendered = Vec::with_capacity(total);
    for (k, (config, name)) in manifest.configurations.iter().zip(&names).enumerate() {
        let mesh_path = run.join(MESHES_DIR).join(format!("{}.ply", config.id));
        let mesh = load_mesh(&mesh_path)?;
        let wanted = TurntableSettings {
            shading: shadings.as_ref().map_or(settings.shading, |s| s[k]),
            elevation_degrees: elevations
                .as_ref()
                .and_then(|e| e[k])
                .unwrap_or(settings.elevation_degrees),
            ..settings.clone()
        };
        let renderer = if wanted == *settings {
            &renderer
        } else {
            let at = match renderers.iter().position(|r| *r.settings() == wanted) {
                Some(at) => at,
                None => {
                    renderers.push(Renderer::new(wanted)?);
                    renderers.len() - 1
                }
            };
            &renderers[at]
        };
        let animation = renderer.render(&mesh).map_err(|e| RenderError::MeshFile {
            path: mesh_path.clone(),
            message: e.to_string(),
        })?;
        let path = render_dir.join(format!("{name}.gif"));
        animation.write_gif(&path)?;
        let bytes = std::fs::metadata(&path).map_err(io_error(&path))?.len();
        let done = RenderedAnimation {
            name: name.clone(),
            id: config.id.clone(),
            path,
            bytes,
        };
        progress(k + 1, total, &done);
        rendered.push(done);
    }
    let settings_path = render_dir.join(SETTINGS_FILE);
    let json =
        serde_json::to_string_pretty(renderer.settings()).map_err(|source| RenderError::Json {
            path: settings_path.clone(),
            source,
        })?;
    std::fs::write(&settings_path, json + "\n").map_err(io_error(&settings_path))?;

    let mut header = vec!["name", "id"];
    header.extend(manifest.variables.iter().map(String::as_str));
    let mut rows: Vec<Vec<String>> = manifest
        .configurations
        .iter()
        .zip(&names)
        .map(|(c, name)| {
            let mut row = vec![name.clone(), c.id.clone()];
            row.extend(c.values.iter().cloned());
            row
        })
        .collect();
    rows.sort();
    write_csv(&key_path, &header, &rows)?;
    Ok(rendered)
}

/// The column of `configurations.csv` that gives each configuration's shading.
pub const SHADING_COLUMN: &str = rmt_runfolder::schema::SHADING;

/// Each configuration's shading, in manifest order, when the configurations have a
/// [`SHADING_COLUMN`] (`None` without one); `path` names the file in errors.
pub fn configuration_shadings(manifest: &Manifest, path: &Path) -> Result<Option<Vec<Shading>>> {
    let Some(column) = manifest.variable_index(SHADING_COLUMN) else {
        return Ok(None);
    };
    manifest
        .configurations
        .iter()
        .map(|c| match c.values[column].as_str() {
            "smooth" => Ok(Shading::Smooth),
            "flat" => Ok(Shading::Flat),
            other => Err(RenderError::BadFile {
                path: path.to_path_buf(),
                message: format!(
                    "configuration `{}`: unknown shading `{other}` (expected smooth or flat)",
                    c.id
                ),
            }),
        })
        .collect::<Result<Vec<_>>>()
        .map(Some)
}

/// The column of `configurations.csv` that gives a configuration's camera elevation in degrees
/// (empty: the render settings').
pub const ELEVATION_COLUMN: &str = rmt_runfolder::schema::ELEVATION;

/// Each configuration's camera elevation, in manifest order (`None` where the cell is empty),
/// when the configurations have an [`ELEVATION_COLUMN`] (`None` without one); `path` names the
/// file in errors.
pub fn configuration_elevations(
    manifest: &Manifest,
    path: &Path,
) -> Result<Option<Vec<Option<f32>>>> {
    let Some(column) = manifest.variable_index(ELEVATION_COLUMN) else {
        return Ok(None);
    };
    manifest
        .configurations
        .iter()
        .map(|c| match c.values[column].as_str() {
            "" => Ok(None),
            text => match text.parse::<f32>() {
                Ok(e) if (-89.0..=89.0).contains(&e) => Ok(Some(e)),
                _ => Err(RenderError::BadFile {
                    path: path.to_path_buf(),
                    message: format!(
                        "configuration `{}`: elevation `{text}` is not a number of degrees in \
                         -89..=89",
                        c.id
                    ),
                }),
            },
        })
        .collect::<Result<Vec<_>>>()
        .map(Some)
}

/// Reads `key.csv`: configuration id -> animation name.
pub fn read_key(path: &Path) -> Result<BTreeMap<String, String>> {
    let csv_error = |source| RenderError::Csv {
        path: path.to_path_buf(),
        source,
    };
    let bad = |message: String| RenderError::BadFile {
        path: path.to_path_buf(),
        message,
    };
    let file = std::fs::File::open(path).map_err(io_error(path))?;
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_reader(file);
    let headers = reader.headers().map_err(csv_error)?.clone();
    let column = |name: &str| {
        headers
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| bad(format!("no `{name}` column")))
    };
    let (name_col, id_col) = (column("name")?, column("id")?);
    let mut key = BTreeMap::new();
    for (row, record) in reader.records().enumerate() {
        let record = record.map_err(csv_error)?;
        let (name, id) = (
            record.get(name_col).unwrap_or(""),
            record.get(id_col).unwrap_or(""),
        );
        if name.is_empty() || !name.bytes().all(|b| b.is_ascii_lowercase()) {
            return Err(bad(format!(
                "line {}: name `{name}` is not lowercase letters",
                row + 2
            )));
        }
        if key.insert(id.to_string(), name.to_string()).is_some() {
            return Err(bad(format!(
                "line {}: configuration `{id}` named twice",
                row + 2
            )));
        }
    }
    Ok(key)
}

/// One written question.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WrittenQuestion {
    /// `Q1`, `Q2`, ...
    pub id: String,
    /// The planned question (manifest indices, kind, variable).
    pub question: Question,
    /// Left and right animation names.
    pub names: (String, String),
    /// The side-by-side GIF.
    pub path: PathBuf,
    /// Its size in bytes.
    pub bytes: u64,
}

/// `experiments questionnaire`: the question set of the run (see [`crate::questionnaire`]) as
/// side-by-side GIFs in `questionnaire/`, with `questions.csv` (question, left name, right name),
/// `questionnaire.html`, and `questionnaire_key.csv` in the run folder.
///
/// `questionnaire_key.csv` starts with `question,left,right` holding configuration ids, the
/// format of `data/questionnaire/questions.csv`, so the analysis can read it as is; further
/// columns: `left_name,right_name,kind,variable,file`.
///
/// Needs `render` to have run: reads `key.csv`, `render/settings.json` (the gap takes the
/// background colour) and `render/<name>.gif`. Earlier `q*.gif` files in `questionnaire/` are
/// removed first.
pub fn build_questionnaire(
    run: &Path,
    options: &QuestionnaireOptions,
    mut progress: impl FnMut(usize, usize, &WrittenQuestion),
) -> Result<Vec<WrittenQuestion>> {
    let manifest = Manifest::read(&run.join(CONFIGURATIONS_FILE))?;
    let key_path = run.join(KEY_FILE);
    if !key_path.exists() {
        return Err(RenderError::Questionnaire(format!(
            "{} is missing: run `experiments render {}` first",
            key_path.display(),
            run.display()
        )));
    }
    let key = read_key(&key_path)?;
    let names: Vec<String> = manifest
        .configurations
        .iter()
        .map(|c| {
            key.get(&c.id).cloned().ok_or_else(|| RenderError::BadFile {
                path: key_path.clone(),
                message: format!("configuration `{}` has no name: render the run again", c.id),
            })
        })
        .collect::<Result<_>>()?;
    let settings = TurntableSettings::read_json(&run.join(RENDER_DIR).join(SETTINGS_FILE))?;

    let questions = plan_questions(&manifest, options)?;
    let out_dir = run.join(QUESTIONNAIRE_DIR);
    std::fs::create_dir_all(&out_dir).map_err(io_error(&out_dir))?;
    remove_stale(&out_dir, |f| f.starts_with('q') && f.ends_with(".gif"))?;

    let decode = |name: &str| -> Result<DecodedGif> {
        decode_gif(&run.join(RENDER_DIR).join(format!("{name}.gif")))
    };
    let total = questions.len();
    let mut written = Vec::with_capacity(total);
    let mut page = Vec::with_capacity(total);
    for (k, question) in questions.into_iter().enumerate() {
        let id = format!("Q{}", k + 1);
        let (l, r) = (names[question.left].clone(), names[question.right].clone());
        let left = decode(&l)?;
        let right = if question.left == question.right {
            left.clone()
        } else {
            decode(&r)?
        };
        let joined = side_by_side(
            &left,
            &right,
            options.gap,
            settings.background,
            options.scale,
            (&l, &r),
        )?;
        let file = question_file_name(k + 1, total, &l, &r);
        let path = out_dir.join(&file);
        joined.write_gif(&path)?;
        let bytes = std::fs::metadata(&path).map_err(io_error(&path))?.len();
        page.push(PageQuestion {
            id: id.clone(),
            file,
            width: u32::from(joined.width),
            height: u32::from(joined.height),
        });
        let done = WrittenQuestion {
            id,
            question,
            names: (l, r),
            path,
            bytes,
        };
        progress(k + 1, total, &done);
        written.push(done);
    }

    let questions_rows: Vec<Vec<String>> = written
        .iter()
        .map(|w| vec![w.id.clone(), w.names.0.clone(), w.names.1.clone()])
        .collect();
    write_csv(
        &out_dir.join(QUESTIONS_FILE),
        &["question", "left", "right"],
        &questions_rows,
    )?;
    let key_rows: Vec<Vec<String>> = written
        .iter()
        .zip(&page)
        .map(|(w, p)| {
            vec![
                w.id.clone(),
                manifest.configurations[w.question.left].id.clone(),
                manifest.configurations[w.question.right].id.clone(),
                w.names.0.clone(),
                w.names.1.clone(),
                w.question.kind.as_str().to_string(),
                w.question.variable.clone().unwrap_or_default(),
                p.file.clone(),
            ]
        })
        .collect();
    write_csv(
        &run.join(QUESTIONNAIRE_KEY_FILE),
        &[
            "question",
            "left",
            "right",
            "left_name",
            "right_name",
            "kind",
            "variable",
            "file",
        ],
        &key_rows,
    )?;
    let html_path = out_dir.join(HTML_FILE);
    std::fs::write(&html_path, questionnaire_html(&page)).map_err(io_error(&html_path))?;
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::names::NAME_LETTERS;
    use crate::shapes::uv_sphere;
    use std::collections::BTreeSet;

    /// A run folder with the paper's 18 configurations; each mesh is a sphere whose resolution
    /// and size depend on the configuration, so the animations differ.
    fn paper_run(dir: &Path) {
        std::fs::write(
            dir.join(CONFIGURATIONS_FILE),
            include_str!("../tests/fixtures/configurations.csv"),
        )
        .unwrap();
        std::fs::create_dir_all(dir.join(MESHES_DIR)).unwrap();
        let manifest = Manifest::read(&dir.join(CONFIGURATIONS_FILE)).unwrap();
        for (k, c) in manifest.configurations.iter().enumerate() {
            let mesh = uv_sphere(1.0 + k as f32 * 0.1, 5 + k as u32, 3 + (k as u32) / 2);
            rmt_mesh::io::save_ply(
                dir.join(MESHES_DIR).join(format!("{}.ply", c.id)),
                &mesh,
                true,
            )
            .unwrap();
        }
    }

    fn tiny_settings() -> TurntableSettings {
        TurntableSettings {
            width: 24,
            height: 20,
            frames: 4,
            supersampling: 2,
            ..TurntableSettings::default()
        }
    }

    fn read_rows(path: &Path) -> Vec<Vec<String>> {
        let mut reader = csv::Reader::from_path(path).unwrap();
        let mut rows = vec![reader.headers().unwrap().iter().map(String::from).collect()];
        rows.extend(
            reader
                .records()
                .map(|r| r.unwrap().iter().map(String::from).collect()),
        );
        rows
    }

    #[test]
    fn render_then_questionnaire_on_the_paper_manifest() {
        let dir = tempfile::tempdir().unwrap();
        let run = dir.path();
        paper_run(run);
        std::fs::create_dir_all(run.join(RENDER_DIR)).unwrap();
        std::fs::write(run.join(RENDER_DIR).join("stale.gif"), b"old").unwrap();
        let rendered = render_run(run, &tiny_settings(), 42, |_, _, _| {}).unwrap();
        assert_eq!(rendered.len(), 18);
        assert!(!run.join(RENDER_DIR).join("stale.gif").exists());

        // Names: unique, four consonants, and independent of the configurations.
        let names: BTreeSet<&str> = rendered.iter().map(|r| r.name.as_str()).collect();
        assert_eq!(names.len(), 18);
        let in_order: Vec<String> = rendered.iter().map(|r| r.name.clone()).collect();
        assert_eq!(
            in_order,
            random_names(18, 42).unwrap(),
            "names come from the seed alone"
        );
        for r in &rendered {
            assert!(r.name.bytes().all(|b| NAME_LETTERS.contains(&b)));
            assert!(!r.name.contains(&r.id) && !r.id.contains(&r.name));
            assert!(r.path.exists() && r.path.parent() == Some(run.join(RENDER_DIR).as_path()));
        }
        // The key is outside render/ and maps names to full configurations.
        let key = read_rows(&run.join(KEY_FILE));
        assert_eq!(key[0], ["name", "id", "object", "lattice", "clustering"]);
        assert_eq!(key.len(), 19);
        assert!(key
            .iter()
            .any(|row| row[1] == "bs_sp" && row[2] == "bunny" && row[4] == "postprocessed"));
        let in_render: Vec<String> = std::fs::read_dir(run.join(RENDER_DIR))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(in_render.len(), 19);
        assert!(in_render
            .iter()
            .all(|f| f == SETTINGS_FILE || f.ends_with(".gif")));
        let settings: TurntableSettings = serde_json::from_str(
            &std::fs::read_to_string(run.join(RENDER_DIR).join(SETTINGS_FILE)).unwrap(),
        )
        .unwrap();
        assert_eq!(settings, tiny_settings());

        let options = QuestionnaireOptions {
            seed: 9,
            reverse_pairs: false,
            controls: 2,
            gap: 3,
            scale: 2,
        };
        let written = build_questionnaire(run, &options, |_, _, _| {}).unwrap();
        assert_eq!(written.len(), 29);
        let by_id: BTreeMap<&str, &str> = rendered
            .iter()
            .map(|r| (r.id.as_str(), r.name.as_str()))
            .collect();
        let questions = read_rows(&run.join(QUESTIONNAIRE_DIR).join(QUESTIONS_FILE));
        let qkey = read_rows(&run.join(QUESTIONNAIRE_KEY_FILE));
        assert_eq!(questions[0], ["question", "left", "right"]);
        assert_eq!(qkey[0][..3], ["question", "left", "right"]);
        for (k, (q, kk)) in questions.iter().zip(&qkey).skip(1).enumerate() {
            assert_eq!(q[0], format!("Q{}", k + 1));
            assert_eq!(kk[0], q[0]);
            assert_eq!(by_id[kk[1].as_str()], q[1]);
            assert_eq!(by_id[kk[2].as_str()], q[2]);
            let file = run.join(QUESTIONNAIRE_DIR).join(&kk[7]);
            assert!(file.exists(), "{}", file.display());
            assert!(kk[7].contains(&q[1]) && kk[7].contains(&q[2]));
        }
        assert_eq!(qkey.iter().filter(|r| r[5] == "control").count(), 2);

        // A question's frames are the two animations upscaled 2x with a 3-pixel gap.
        let w = &written[0];
        let joined = decode_gif(&w.path).unwrap();
        let left = decode_gif(&run.join(RENDER_DIR).join(format!("{}.gif", w.names.0))).unwrap();
        let right = decode_gif(&run.join(RENDER_DIR).join(format!("{}.gif", w.names.1))).unwrap();
        assert_eq!((joined.width, joined.height), ((24 * 2 + 3) * 2, 40));
        assert_eq!(joined.frames.len(), 4);
        for k in 0..4 {
            for y in 0..40usize {
                for x in 0..102usize {
                    let (sx, sy) = (x / 2, y / 2);
                    let expected = if sx < 24 {
                        left.frames[k][sy * 24 + sx]
                    } else if sx < 27 {
                        let b = settings.background;
                        [b[0], b[1], b[2], 255]
                    } else {
                        right.frames[k][sy * 24 + sx - 27]
                    };
                    assert_eq!(
                        joined.frames[k][y * 102 + x],
                        expected,
                        "frame {k} ({x}, {y})"
                    );
                }
            }
        }
        let html = std::fs::read_to_string(run.join(QUESTIONNAIRE_DIR).join(HTML_FILE)).unwrap();
        assert!(html.contains(&format!(r#"src="{}""#, qkey[1][7])));
        assert_eq!(html.matches("<section class=\"question\"").count(), 29);
    }

    #[test]
    fn questionnaire_without_render_says_what_to_run() {
        let dir = tempfile::tempdir().unwrap();
        paper_run(dir.path());
        let err = build_questionnaire(dir.path(), &QuestionnaireOptions::default(), |_, _, _| {})
            .unwrap_err();
        assert!(err.to_string().contains("experiments render"), "{err}");
    }

    #[test]
    fn a_shading_column_draws_each_configuration_with_its_own_shading() {
        let dir = tempfile::tempdir().unwrap();
        let run = dir.path();
        std::fs::write(
            run.join(CONFIGURATIONS_FILE),
            "id,object,clustering,shading\n\
             a,sphere,none,smooth\n\
             a_flat,sphere,none,flat\n\
             b,sphere,integrated,smooth\n",
        )
        .unwrap();
        std::fs::create_dir_all(run.join(MESHES_DIR)).unwrap();
        let mesh = uv_sphere(1.0, 9, 5);
        for id in ["a", "a_flat", "b"] {
            rmt_mesh::io::save_ply(run.join(MESHES_DIR).join(format!("{id}.ply")), &mesh, true)
                .unwrap();
        }
        let rendered = render_run(run, &tiny_settings(), 3, |_, _, _| {}).unwrap();
        let bytes = |i: usize| std::fs::read(&rendered[i].path).unwrap();
        // Same mesh: smooth twice gives the same bytes, flat differs.
        assert_eq!(bytes(0), bytes(2));
        assert_ne!(bytes(0), bytes(1));
        // The flat one is what a flat-shaded render of the same mesh gives.
        let flat = TurntableSettings {
            shading: Shading::Flat,
            ..tiny_settings()
        };
        let alone = Renderer::new(flat.clone()).unwrap().render(&mesh).unwrap();
        let path = run.join("alone.gif");
        alone.write_gif(&path).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), bytes(1));
        let key = read_rows(&run.join(KEY_FILE));
        assert_eq!(key[0], ["name", "id", "object", "clustering", "shading"]);
        // The run decides the shading: flat settings are refused.
        let err = render_run(run, &flat, 3, |_, _, _| {}).unwrap_err();
        assert!(err.to_string().contains("shading"), "{err}");
        // An unknown shading is named.
        std::fs::write(
            run.join(CONFIGURATIONS_FILE),
            "id,object,shading\na,sphere,toon\n",
        )
        .unwrap();
        let err = render_run(run, &tiny_settings(), 3, |_, _, _| {}).unwrap_err();
        assert!(err.to_string().contains("toon"), "{err}");
    }

    #[test]
    fn an_elevation_column_draws_those_configurations_from_their_elevation() {
        let dir = tempfile::tempdir().unwrap();
        let run = dir.path();
        std::fs::write(
            run.join(CONFIGURATIONS_FILE),
            "id,object,shading,elevation_deg\n\
             a,sphere,smooth,\n\
             c,chunk,smooth,55\n\
             c_flat,chunk,flat,55\n",
        )
        .unwrap();
        std::fs::create_dir_all(run.join(MESHES_DIR)).unwrap();
        // A squashed sphere, so that the elevation shows in the image.
        let mut mesh = uv_sphere(1.0, 9, 5);
        mesh.positions.iter_mut().for_each(|p| p[1] *= 0.3);
        for id in ["a", "c", "c_flat"] {
            rmt_mesh::io::save_ply(run.join(MESHES_DIR).join(format!("{id}.ply")), &mesh, true)
                .unwrap();
        }
        let rendered = render_run(run, &tiny_settings(), 3, |_, _, _| {}).unwrap();
        let bytes = |i: usize| std::fs::read(&rendered[i].path).unwrap();
        let alone = |settings: TurntableSettings| {
            let path = run.join("alone.gif");
            let animation = Renderer::new(settings).unwrap().render(&mesh).unwrap();
            animation.write_gif(&path).unwrap();
            std::fs::read(&path).unwrap()
        };
        // No value: the settings' elevation; a value: that elevation, with its own shading.
        assert_eq!(bytes(0), alone(tiny_settings()));
        let above = TurntableSettings {
            elevation_degrees: 55.0,
            ..tiny_settings()
        };
        assert_eq!(bytes(1), alone(above.clone()));
        assert_ne!(bytes(0), bytes(1));
        let flat_above = TurntableSettings {
            shading: Shading::Flat,
            ..above
        };
        assert_eq!(bytes(2), alone(flat_above));
        // settings.json keeps the settings the run was rendered with.
        let settings: TurntableSettings = serde_json::from_str(
            &std::fs::read_to_string(run.join(RENDER_DIR).join(SETTINGS_FILE)).unwrap(),
        )
        .unwrap();
        assert_eq!(settings, tiny_settings());
        // An elevation out of range is named.
        std::fs::write(
            run.join(CONFIGURATIONS_FILE),
            "id,object,elevation_deg\na,sphere,95\n",
        )
        .unwrap();
        let err = render_run(run, &tiny_settings(), 3, |_, _, _| {}).unwrap_err();
        assert!(err.to_string().contains("elevation `95`"), "{err}");
    }

    #[test]
    fn missing_mesh_is_named() {
        let dir = tempfile::tempdir().unwrap();
        paper_run(dir.path());
        std::fs::remove_file(dir.path().join(MESHES_DIR).join("as_bi.ply")).unwrap();
        let err = render_run(dir.path(), &tiny_settings(), 1, |_, _, _| {}).unwrap_err();
        assert!(err.to_string().contains("as_bi.ply"), "{err}");
    }
}
