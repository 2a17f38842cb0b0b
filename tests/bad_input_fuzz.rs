//! Bad input in bulk: seeded mutations of valid scene TOML, Abaqus `.inp`, Gmsh `.msh` and
//! Matrix Market files (truncations, deleted, duplicated and swapped lines, numbers replaced by
//! NaN, Inf, 1e400, huge, zero or negative values, random bytes, edited keys and keywords).
//!
//! Every case must end either in an error that names the file and the line or key, or in a
//! result that passes what the program checks before it uses one (a scene that validated; a
//! mesh whose coordinates are finite, whose materials are admissible and whose elements all
//! have a positive Jacobian; matrix entries that are finite and inside the matrix). Never a
//! panic, and (through nextest's time limit) never a hang. The seeds are the scenes of jobs/
//! and the files of tests/data/seeds; the cases are the same on every run (fixed seeds).

use std::collections::BTreeMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use squeal::mesh::material::Material;
use squeal::scene::Scene;

/// Cases per seed file.
const CASES: usize = 2000;

/// SplitMix64: a seeded stream, so that a failing case can be replayed from its number.
struct Stream(u64);

impl Stream {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// What replaces a number: the values a reader must refuse or survive.
const BAD_NUMBERS: &[&str] = &[
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e400",
    "-1e400",
    "1e308",
    "0",
    "0.0",
    "-1",
    "-1.0e11",
    "99999999999999999999999",
    "4294967296",
    "1e-320",
    "",
    "1..2",
    "0x10",
];

/// One mutation of `text`, chosen by the stream; `keys` are words worth editing (scene keys,
/// keywords), found in the text by the caller.
fn mutate(text: &str, s: &mut Stream) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let n = lines.len();
    match s.below(9) {
        0 => {
            // Truncation at a character boundary.
            let mut cut = s.below(text.len());
            while !text.is_char_boundary(cut) {
                cut -= 1;
            }
            return text[..cut].to_string();
        }
        1 => {
            lines.remove(s.below(n));
        }
        2 => {
            let i = s.below(n);
            lines.insert(i, lines[i].clone());
        }
        3 => {
            let (i, j) = (s.below(n), s.below(n));
            lines.swap(i, j);
        }
        4 | 5 => {
            // A number replaced (twice as likely: most of these files are numbers).
            let spans = number_spans(text);
            if spans.is_empty() {
                return text.to_string();
            }
            let (a, b) = spans[s.below(spans.len())];
            let bad = BAD_NUMBERS[s.below(BAD_NUMBERS.len())];
            let bad = if bad == "-1" {
                format!("-{}", &text[a..b].trim_start_matches('-'))
            } else {
                bad.to_string()
            };
            return format!("{}{bad}{}", &text[..a], &text[b..]);
        }
        6 => {
            // Random bytes (kept valid UTF-8: the readers take text) at a random place.
            let at = s.below(n);
            let junk: String = (0..1 + s.below(8))
                .map(|_| char::from_u32(s.below(0x250) as u32).unwrap_or('?'))
                .collect();
            let line = &mut lines[at];
            let mut pos = s.below(line.len() + 1);
            while !line.is_char_boundary(pos) {
                pos -= 1;
            }
            line.insert_str(pos, &junk);
        }
        7 => {
            // A word (key, keyword, section name) edited: a letter doubled or dropped.
            let words = word_spans(text);
            if words.is_empty() {
                return text.to_string();
            }
            let (a, b) = words[s.below(words.len())];
            let word = &text[a..b];
            let edited = if s.below(2) == 0 {
                format!("{word}x")
            } else {
                word[..word.len() - 1].to_string()
            };
            return format!("{}{edited}{}", &text[..a], &text[b..]);
        }
        _ => {
            // A whole line blanked or the file emptied.
            if s.below(10) == 0 {
                return String::new();
            }
            lines[s.below(n)].clear();
        }
    }
    let mut out = lines.join("\n");
    out.push('\n');
    out
}

/// Byte ranges of the numbers in `text` (digits with sign, point and exponent).
fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts = b[i].is_ascii_digit()
            && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_'));
        if starts {
            let a = if i > 0 && b[i - 1] == b'-' { i - 1 } else { i };
            let mut j = i;
            while j < b.len() && (b[j].is_ascii_digit() || b".eE+-_".contains(&b[j])) {
                j += 1;
            }
            spans.push((a, j));
            i = j;
        } else {
            i += 1;
        }
    }
    spans
}

/// Byte ranges of the words (letters and underscores, at least 3) in `text`.
fn word_spans(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_alphabetic() {
            let mut j = i;
            while j < b.len() && (b[j].is_ascii_alphabetic() || b[j] == b'_') {
                j += 1;
            }
            if j - i >= 3 {
                spans.push((i, j));
            }
            i = j;
        } else {
            i += 1;
        }
    }
    spans
}

/// An error message is useful when it names the file and where in it: a line (`file:12`,
/// "line 12"), a key or keyword (quoted, or a table path), a numbered node or element, or, for what is missing
/// from the whole file, what is missing ("no elements", "no $MeshFormat section").
fn names_file_and_place(message: &str, file: &str) -> bool {
    let numbered = |word: &str| {
        message
            .split(word)
            .skip(1)
            .any(|rest| rest.starts_with(|c: char| c.is_ascii_digit()))
    };
    let place = numbered(&format!("{file}:"))
        || numbered("line ")
        || numbered("node ")
        || numbered("element ")
        || message.contains("key")
        || message.contains('\'')
        || message.contains('`')
        || message.contains(": no ")
        || message.split(": ").any(is_dotted_key);
    message.contains(file) && place
}

/// A scene key path such as `model.geometry`, as the validation names a table.
fn is_dotted_key(word: &str) -> bool {
    word.contains('.')
        && word
            .split('.')
            .all(|p| !p.is_empty() && p.chars().all(|c| c.is_ascii_lowercase() || c == '_'))
}

/// Runs `cases` mutations of `seed` through `read` (which gets the path of the mutated file and
/// returns Ok(None) when the result passed its checks, Ok(Some(why)) when it did not, or the
/// error message). Collects the cases that panicked, gave a useless error, or garbage.
fn fuzz(
    name: &str,
    seed_text: &str,
    seed: u64,
    cases: usize,
    read: &dyn Fn(&Path) -> Result<Option<String>, String>,
) -> (usize, Vec<String>) {
    let dir = scratch(name);
    let mut s = Stream(seed);
    let mut bad = Vec::new();
    let mut errors = 0;
    for case in 0..cases {
        let text = mutate(seed_text, &mut s);
        let file = format!("case{case}-{name}");
        let path = dir.join(&file);
        std::fs::write(&path, &text).unwrap();
        match catch_unwind(AssertUnwindSafe(|| read(&path))) {
            Err(panic) => {
                let what = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                bad.push(format!("{file}: panicked: {what}"));
            }
            Ok(Err(message)) => {
                errors += 1;
                if !names_file_and_place(&message, &file) {
                    bad.push(format!("{file}: error without file and place: {message}"));
                }
            }
            Ok(Ok(Some(garbage))) => bad.push(format!("{file}: accepted garbage: {garbage}")),
            Ok(Ok(None)) => {}
        }
        if bad.len() < 20 && !bad.is_empty() && bad.last().unwrap().starts_with(&file) {
            std::fs::copy(&path, dir.join(format!("{file}.kept"))).ok();
        }
    }
    (errors, bad)
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("squeal-fuzz-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn report(what: &str, cases: usize, errors: usize, bad: &[String]) {
    println!(
        "{what}: {cases} cases, {errors} refused with an error, {} bad",
        bad.len()
    );
    assert!(
        bad.is_empty(),
        "{what}: {} of {cases} cases went wrong, first ones:\n{}",
        bad.len(),
        bad.iter().take(15).cloned().collect::<Vec<_>>().join("\n")
    );
}

/// What the pipeline does with an imported mesh before it uses it: the reader's result, then
/// the element check (a non-positive or non-finite Jacobian anywhere is an error that names
/// the element and block, with the file's name first, as the import stage gives it).
/// Ok(None) when the mesh goes on, Ok(Some(why)) when it is garbage that went through.
fn import_checks(
    mesh: Result<squeal::mesh::Mesh, String>,
    path: &Path,
) -> Result<Option<String>, String> {
    let mesh = mesh?;
    squeal::fem::quality::check(&mesh).map_err(|e| format!("{}: {e}", path.display()))?;
    if let Some(x) = mesh.coords.iter().flatten().find(|x| !x.is_finite()) {
        return Ok(Some(format!("coordinate {x}")));
    }
    Ok(mesh
        .materials
        .iter()
        .find_map(|m| m.validate().err())
        .map(|e| e.to_string()))
}

/// The first non-finite number of a validated scene, with its key: no key of a scene takes
/// NaN or an infinity, so one that got through is garbage.
fn non_finite(value: &toml::Value, key: &str) -> Option<String> {
    match value {
        toml::Value::Float(x) if !x.is_finite() => Some(format!("{key} = {x}")),
        toml::Value::Table(t) => t
            .iter()
            .find_map(|(k, v)| non_finite(v, &format!("{key}.{k}"))),
        toml::Value::Array(a) => a
            .iter()
            .enumerate()
            .find_map(|(i, v)| non_finite(v, &format!("{key}[{i}]"))),
        _ => None,
    }
}

#[test]
fn mutated_scenes_are_refused_with_file_and_key_or_validate() {
    let jobs = Path::new(env!("CARGO_MANIFEST_DIR")).join("jobs");
    let mut seeds: Vec<PathBuf> = std::fs::read_dir(&jobs)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    seeds.sort();
    assert!(seeds.len() >= 5, "scenes in jobs/: {seeds:?}");
    let (mut cases, mut errors, mut bad) = (0, 0, Vec::new());
    for (k, seed) in seeds.iter().enumerate() {
        let text = std::fs::read_to_string(seed).unwrap();
        let name = seed.file_name().unwrap().to_string_lossy().to_string();
        let (e, b) = fuzz(&name, &text, 1000 + k as u64, CASES / 2, &|path| {
            let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
            let file = path.file_name().unwrap().to_string_lossy().to_string();
            Scene::parse(&text, &file)
                .map(|scene| non_finite(&toml::Value::try_from(&scene).unwrap(), "scene"))
                .map_err(|e| e.to_string())
        });
        cases += CASES / 2;
        errors += e;
        bad.extend(b);
    }
    report("scene TOML", cases, errors, &bad);
}

#[test]
fn mutated_abaqus_inp_files_are_refused_with_file_and_line_or_give_a_valid_mesh() {
    let seed = include_str!("data/seeds/two_hexes.inp");
    let (errors, bad) = fuzz("two_hexes.inp", seed, 2, CASES, &|path| {
        let mesh = squeal::mesh::abaqus_inp::read(path).map(|m| m.mesh);
        import_checks(mesh.map_err(|e| e.to_string()), path)
    });
    report("Abaqus .inp", CASES, errors, &bad);
}

#[test]
fn mutated_gmsh_files_are_refused_with_file_and_line_or_give_a_valid_mesh() {
    let seed = include_str!("data/seeds/two_cubes.msh");
    let steel = Material::isotropic("steel", 210e9, 0.3, 7850.0);
    let materials: BTreeMap<String, Material> = ["disc", "pad"]
        .iter()
        .map(|n| (n.to_string(), steel.clone()))
        .collect();
    let (errors, bad) = fuzz("two_cubes.msh", seed, 3, CASES, &|path| {
        let mesh = squeal::mesh::gmsh_msh::read(path, &materials).map(|m| m.mesh);
        import_checks(mesh.map_err(|e| e.to_string()), path)
    });
    report("Gmsh .msh", CASES, errors, &bad);
}

#[test]
fn mutated_matrix_market_files_are_refused_with_file_and_line_or_give_finite_entries() {
    // A small symmetric positive definite matrix in the coordinate format of the exported and
    // imported operators (lower triangle stored).
    let seed = "%%MatrixMarket matrix coordinate real symmetric\n\
        % brake M0 mass, leading entries\n\
        6 6 9\n\
        1 1 2.5e-3\n2 2 2.5e-3\n3 3 2.5e-3\n4 1 6.25e-4\n4 4 5.0e-3\n5 2 6.25e-4\n\
        5 5 5.0e-3\n6 3 6.25e-4\n6 6 5.0e-3\n";
    let (errors, bad) = fuzz("m.mtx", seed, 4, CASES, &|path| {
        squeal::io::matrix_market::read(path)
            .map(|t| {
                t.entries.iter().find_map(|&(i, j, v)| {
                    let inside = (i as usize) < t.rows && (j as usize) < t.cols;
                    (!inside || !v.is_finite()).then(|| format!("entry ({i}, {j}) = {v}"))
                })
            })
            .map_err(|e| e.to_string())
    });
    report("Matrix Market", CASES, errors, &bad);
}

/// `squeal check` on mutated scenes that validate: a model that cannot be built, paired or
/// estimated is an error, never a panic. Small seeds only (a mutated target size up to 40k
/// DOF), so that the cases build their models in a second.
#[test]
fn squeal_check_on_mutated_scenes_never_panics() {
    let jobs = Path::new(env!("CARGO_MANIFEST_DIR")).join("jobs");
    let seeds = ["default.toml", "disc-and-pads.toml", "disc-ring-modes.toml"];
    let (mut cases, mut errors, mut bad) = (0, 0, Vec::new());
    for (k, name) in seeds.iter().enumerate() {
        let text = std::fs::read_to_string(jobs.join(name)).unwrap();
        let (e, b) = fuzz(
            &format!("check-{name}"),
            &text,
            7000 + k as u64,
            150,
            &|path| {
                let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
                let file = path.file_name().unwrap().to_string_lossy().to_string();
                let scene = Scene::parse(&text, &file).map_err(|e| e.to_string())?;
                let value = toml::Value::try_from(&scene).unwrap();
                let dofs = value
                    .get("model")
                    .and_then(|m| m.get("target_dofs"))
                    .and_then(toml::Value::as_integer);
                if dofs.is_some_and(|d| d > 40_000) {
                    return Ok(None);
                }
                // The check's errors name the scene file first, as `squeal check` prints them.
                squeal::stages::check::check(&scene, &jobs, 2)
                    .map(|_| None)
                    .map_err(|e| format!("{file}: {e}"))
            },
        );
        cases += 150;
        errors += e;
        bad.extend(b);
    }
    report("squeal check", cases, errors, &bad);
}

#[path = "support/launch.rs"]
mod launch;

/// Whole runs under mpirun of mutated small scenes (a brake of 3,000 DOF with its preload
/// and complex modes, an annulus): each ends in squeal's error exit naming the scene, or in
/// a run that wrote its results; never a panic, a signal or a hang. The seed changes each
/// run and is printed (`SQUEAL_FUZZ_SEED=<seed>` replays it); cases run until 90 s have
/// passed, at least 50 of them. A case that validated but asks for more than the seed's
/// size (DOF, modes) is skipped: its cost is a benchmark's, not a test's.
#[test]
fn mutated_scenes_run_whole_under_mpirun_end_cleanly() {
    let seed = std::env::var("SQUEAL_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| {
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .unwrap()
                .as_secs()
        });
    println!("whole runs: seed {seed} (SQUEAL_FUZZ_SEED={seed} replays them)");
    let brake = "[model]\nsource = \"brake\"\ntarget_dofs = 3000\npressure_bar = 20.0\n\
                 [statics]\n[real_modes]\ncount = 12\n[complex_modes]\n";
    let annulus = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("jobs/disc-ring-modes.toml"),
    )
    .unwrap();
    let seeds = [brake.to_string(), annulus];
    let dir = scratch("whole-runs");
    let mut s = Stream(seed);
    let start = std::time::Instant::now();
    let (mut ran, mut refused, mut skipped, mut bad) = (0, 0, 0, Vec::new());
    let mut case = 0;
    while ran < 50 || start.elapsed().as_secs() < 90 {
        assert!(start.elapsed().as_secs() < 900, "50 cases took over 900 s");
        case += 1;
        let text = mutate(&seeds[case % 2], &mut s);
        if let Ok(scene) = Scene::parse(&text, "scene.toml") {
            let value = toml::Value::try_from(&scene).unwrap();
            let model = value.get("model");
            let int = |t: Option<&toml::Value>, k: &str| {
                t.and_then(|t| t.get(k)).and_then(toml::Value::as_integer)
            };
            let count = int(value.get("real_modes"), "count");
            let too_big = int(model, "target_dofs").is_some_and(|d| d > 3000)
                || count.is_some_and(|c| c > 30)
                || scene
                    .real_modes
                    .as_ref()
                    .is_some_and(|r| r.f_max_hz.is_some())
                || model
                    .and_then(|m| m.get("cells"))
                    .and_then(toml::Value::as_array)
                    .is_some_and(|c| {
                        c.iter()
                            .filter_map(toml::Value::as_integer)
                            .product::<i64>()
                            > 8 * 120 * 4
                    });
            if too_big {
                skipped += 1;
                continue;
            }
        }
        let case_dir = dir.join(format!("case{case}"));
        std::fs::create_dir_all(&case_dir).unwrap();
        std::fs::write(case_dir.join("scene.toml"), &text).unwrap();
        let deadline = std::time::Duration::from_secs(120);
        let args = ["run", "scene.toml", "-o", "out"];
        let env = [("SQUEAL_PROGRESS", "0")];
        let out = launch::squeal_run(2, &args, &case_dir, &env, deadline);
        ran += 1;
        let what = format!("case {case} (seed {seed})");
        match out.status.and_then(|s| s.code()) {
            None => bad.push(format!(
                "{what}: hung or killed by a signal\n{}",
                out.stderr
            )),
            Some(0) => {
                if !case_dir.join("out/results.h5").is_file() {
                    bad.push(format!("{what}: exit 0 without results.h5"));
                }
            }
            Some(1) if out.stderr.contains("scene.toml") || out.stderr.contains("error") => {
                refused += 1;
                // What was written before the error still opens.
                let results = case_dir.join("out/results.h5");
                if results.is_file() && hdf5::File::open(&results).is_err() {
                    bad.push(format!("{what}: results.h5 left unreadable"));
                }
            }
            Some(code) => bad.push(format!(
                "{what}: exit {code}\n{}\n{}",
                out.stdout, out.stderr
            )),
        }
        if bad.last().is_some_and(|b| b.starts_with(&what)) {
            std::fs::copy(
                case_dir.join("scene.toml"),
                dir.join(format!("case{case}.kept")),
            )
            .ok();
        }
    }
    println!(
        "whole runs: {ran} run ({refused} refused with an error), {skipped} skipped as too large, in {:.0} s",
        start.elapsed().as_secs_f64()
    );
    assert!(
        bad.is_empty(),
        "{} of {ran} runs went wrong:\n{}",
        bad.len(),
        bad.join("\n")
    );
}
