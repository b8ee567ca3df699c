//! `nimbus cluster scene.pbrt --tiles N | --seeds K | --cameras FILE --out DIR`: one render
//! split into a Slurm job array. Writes, for users to read and edit before submitting:
//!
//! - `tasks.txt`: the exact command of each task, one per line (line i+1 is task i);
//! - `render.sbatch`: the array job (`sbatch --array=0-(n-1)`), running its line of tasks.txt;
//! - `precompute.sbatch`: for methods that precompute (the radiance graph's `graph build`,
//!   guided's training), a job the array depends on (`--dependency=afterok`), whose file every
//!   task then reads;
//! - `submit.sh`: the `sbatch` commands `--submit` runs;
//! - `cluster.json`: the manifest `nimbus merge` and `--resume` read.
//!
//! Each task writes its part under a temporary name and renames it when complete, so a task
//! that fails or is cancelled leaves no part, and `--resume DIR` resubmits exactly the missing.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

use anyhow::{Context, Result, bail};
use nimbus::integrators::registry::Precompute;
use serde_json::{Value, json};

/// Arguments of `nimbus cluster`.
#[derive(clap::Args)]
pub struct ClusterArgs {
    /// Scene file.
    #[arg(required_unless_present = "resume")]
    scene: Option<PathBuf>,
    /// Split the image into N horizontal strips, one task each (merged bit for bit).
    #[arg(long, value_name = "N")]
    tiles: Option<u32>,
    /// Render K independent batches of the whole image with seeds s, s+1, ... (merged by an
    /// spp-weighted average: K times the spp).
    #[arg(long, value_name = "K")]
    seeds: Option<u32>,
    /// One frame per camera of FILE (a `LookAt ex ey ez lx ly lz ux uy uz` line each, `#`
    /// comments), e.g. an orbit rendered from one saved radiance graph.
    #[arg(long, value_name = "FILE")]
    cameras: Option<PathBuf>,
    /// Integrator of every task (default: the scene's).
    #[arg(long)]
    integrator: Option<String>,
    /// Samples per pixel of every task (default: the scene's).
    #[arg(long)]
    spp: Option<u32>,
    /// Sampler seed (of the first batch with --seeds; default: the scene's).
    #[arg(long)]
    seed: Option<i32>,
    /// Folder for the scripts, the parts and the logs.
    #[arg(long, required_unless_present = "resume")]
    out: Option<PathBuf>,
    /// Submit with `sbatch` and print the job ids.
    #[arg(long)]
    submit: bool,
    /// Resubmit the tasks of DIR (a folder `nimbus cluster` wrote) whose parts are missing.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["scene", "tiles", "seeds", "cameras", "out"])]
    resume: Option<PathBuf>,
    /// CPUs per task (`#SBATCH --cpus-per-task` and the task's `--nthreads`).
    #[arg(long, default_value_t = 1)]
    cpus_per_task: u32,
    /// A further `#SBATCH` option for every job, e.g. `--sbatch=--partition=long` (repeatable).
    #[arg(long = "sbatch", value_name = "OPTION", allow_hyphen_values = true)]
    sbatch_options: Vec<String>,
}

/// One task: its part's file (relative to the folder) and its exact command.
#[derive(Clone, Debug, PartialEq)]
pub struct Task {
    /// The part it writes, relative to the cluster folder.
    pub output: String,
    /// The command, as arguments.
    pub command: Vec<String>,
}

/// What `cluster.json` records.
#[derive(Clone, Debug, PartialEq)]
pub struct Manifest {
    /// The scene file (absolute).
    pub scene: PathBuf,
    /// Its hash (as in the parts' metadata).
    pub scene_hash: String,
    /// "tiles", "seeds" or "cameras".
    pub mode: String,
    /// The precomputation, if the method has one: its file (relative) and command.
    pub precompute: Option<Task>,
    /// The array's tasks, in index order.
    pub tasks: Vec<Task>,
    /// `--cpus-per-task`.
    pub cpus_per_task: u32,
    /// `--sbatch` options.
    pub sbatch_options: Vec<String>,
}

fn task_json(t: &Task) -> Value {
    json!({ "output": t.output, "command": t.command })
}

fn task_from(v: &Value, path: &Path) -> Result<Task> {
    let bad = || anyhow::anyhow!("{}: a task is not {{\"output\": ..., \"command\": [...]}}", path.display());
    let output = v.get("output").and_then(Value::as_str).ok_or_else(bad)?.to_string();
    let command = v
        .get("command")
        .and_then(Value::as_array)
        .ok_or_else(bad)?
        .iter()
        .map(|a| a.as_str().map(String::from).ok_or_else(bad))
        .collect::<Result<Vec<_>>>()?;
    Ok(Task { output, command })
}

impl Manifest {
    /// Writes `cluster.json`.
    pub fn write(&self, path: &Path) -> Result<()> {
        let v = json!({
            "version": 1,
            "scene": self.scene.display().to_string(),
            "scene_hash": self.scene_hash,
            "mode": self.mode,
            "precompute": self.precompute.as_ref().map(task_json),
            "tasks": self.tasks.iter().map(task_json).collect::<Vec<_>>(),
            "cpus_per_task": self.cpus_per_task,
            "sbatch_options": self.sbatch_options,
        });
        let text = serde_json::to_string_pretty(&v).expect("JSON values serialize");
        std::fs::write(path, text + "\n").with_context(|| format!("writing {}", path.display()))
    }

    /// Reads `cluster.json`.
    pub fn read(path: &Path) -> Result<Manifest> {
        let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        let v: Value =
            serde_json::from_str(&text).with_context(|| format!("{}: not JSON (a cluster.json?)", path.display()))?;
        let field = |k: &str| v.get(k).with_context(|| format!("{}: no \"{k}\"", path.display()));
        let string = |k: &str| -> Result<String> {
            field(k)?.as_str().map(String::from).with_context(|| format!("{}: \"{k}\" is not a string", path.display()))
        };
        if field("version")?.as_u64() != Some(1) {
            bail!("{}: version {} (this nimbus reads 1)", path.display(), field("version")?);
        }
        let tasks = field("tasks")?
            .as_array()
            .with_context(|| format!("{}: \"tasks\" is not a list", path.display()))?
            .iter()
            .map(|t| task_from(t, path))
            .collect::<Result<Vec<_>>>()?;
        let precompute = match field("precompute")? {
            Value::Null => None,
            t => Some(task_from(t, path)?),
        };
        let sbatch_options = field("sbatch_options")?
            .as_array()
            .with_context(|| format!("{}: \"sbatch_options\" is not a list", path.display()))?
            .iter()
            .filter_map(|o| o.as_str().map(String::from))
            .collect();
        Ok(Manifest {
            scene: PathBuf::from(string("scene")?),
            scene_hash: string("scene_hash")?,
            mode: string("mode")?,
            precompute,
            tasks,
            cpus_per_task: field("cpus_per_task")?.as_u64().unwrap_or(1) as u32,
            sbatch_options,
        })
    }
}

/// `arg` quoted for a POSIX shell when it needs it.
pub fn shell_quote(arg: &str) -> String {
    let plain = !arg.is_empty() && arg.chars().all(|c| c.is_ascii_alphanumeric() || "-_./=:,+@%".contains(c));
    if plain { arg.to_string() } else { format!("'{}'", arg.replace('\'', "'\\''")) }
}

fn shell_line(args: &[String]) -> String {
    args.iter().map(|a| shell_quote(a)).collect::<Vec<_>>().join(" ")
}

/// The cameras of a `--cameras` file: nine numbers per line (`LookAt` optional).
pub fn read_cameras(path: &Path) -> Result<Vec<[f64; 9]>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let mut cameras = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let line = line.strip_prefix("LookAt").unwrap_or(line);
        let v: Vec<f64> = line
            .split_whitespace()
            .map(|x| x.parse::<f64>().ok().filter(|v| v.is_finite()))
            .collect::<Option<_>>()
            .with_context(|| format!("{}:{}: not numbers: \"{line}\"", path.display(), i + 1))?;
        let camera = <[f64; 9]>::try_from(v.clone()).map_err(|_| {
            anyhow::anyhow!(
                "{}:{}: {} numbers; a camera is LookAt's nine (eye, look-at point, up)",
                path.display(),
                i + 1,
                v.len()
            )
        })?;
        if nimbus::parser::transform::look_at(
            [camera[0], camera[1], camera[2]],
            [camera[3], camera[4], camera[5]],
            [camera[6], camera[7], camera[8]],
        )
        .is_none()
        {
            bail!("{}:{}: the view direction is zero or parallel to up", path.display(), i + 1);
        }
        cameras.push(camera);
    }
    if cameras.is_empty() {
        bail!("{} lists no cameras", path.display());
    }
    Ok(cameras)
}

fn absolute(p: &Path) -> Result<PathBuf> {
    std::path::absolute(p).with_context(|| format!("resolving {}", p.display()))
}

/// Builds the manifest for a new split.
fn plan(args: &ClusterArgs, scene: &Path, out: &Path) -> Result<Manifest> {
    let splits = [args.tiles.is_some(), args.seeds.is_some(), args.cameras.is_some()];
    if splits.iter().filter(|s| **s).count() != 1 {
        bail!("give one of --tiles N, --seeds K or --cameras FILE");
    }
    let desc = nimbus::parser::load_file(scene).map_err(|e| anyhow::anyhow!("{e}"))?;
    let opts = nimbus::scene::BuildOptions {
        integrator: args.integrator.clone(),
        scene_file: Some(scene.to_path_buf()),
        spp: args.spp,
        seed: args.seed,
        ..Default::default()
    };
    // Building checks the scene and the integrator once here, not in every task.
    let nimbus::setup::Setup { scene: built, integrator: method } =
        nimbus::setup::build(&desc, &opts).map_err(|e| anyhow::anyhow!("{e}"))?;
    let integrator = method.name();
    // x0 x1 y0 y1, as --pixelbounds takes them.
    let fb = {
        let b = built.film_bounds;
        [b[0], b[2], b[1], b[3]]
    };
    let exe = std::env::current_exe().context("finding the nimbus executable")?;
    let scene_abs = absolute(scene)?;
    let out = absolute(out)?;
    let mut base: Vec<String> = vec![
        exe.display().to_string(),
        "render".into(),
        scene_abs.display().to_string(),
        "--integrator".into(),
        integrator.into(),
        "--nthreads".into(),
        args.cpus_per_task.to_string(),
        "--quiet".into(),
    ];
    let seed = built.sampler.seed;
    // The method says what it prepares before its renders; every render task then reads it.
    let precompute = match method.precompute(&scene_abs).map_err(anyhow::Error::msg)? {
        None => None,
        Some(Precompute::Command { args, file }) => {
            base.extend(["--precomputed".into(), out.join(&file).display().to_string()]);
            let mut command = vec![exe.display().to_string()];
            command.extend(args);
            command.push(out.join(&file).parent().unwrap_or(&out).display().to_string());
            Some(Task { output: file, command })
        }
        Some(Precompute::FirstRender { file }) => {
            base.extend(["--precomputed".into(), out.join(&file).display().to_string()]);
            // One pixel at one sample renders it.
            let mut command = base.clone();
            command.extend(["--seed".into(), seed.to_string(), "--spp".into(), "1".into()]);
            command.extend(["--pixelbounds".into(), fb[0].to_string(), (fb[0] + 1).to_string()]);
            command.extend([fb[2].to_string(), (fb[2] + 1).to_string(), "--outfile".into()]);
            command.push(out.join("logs/precompute.exr").display().to_string());
            Some(Task { output: file, command })
        }
    };
    if let Some(spp) = args.spp {
        base.extend(["--spp".into(), spp.to_string()]);
    }
    let mut tasks = Vec::new();
    let mut push = |output: String, extra: Vec<String>| {
        let mut command = base.clone();
        command.extend(extra);
        command.extend(["--outfile".into(), out.join(&output).display().to_string()]);
        tasks.push(Task { output, command });
    };
    let mode = if let Some(n) = args.tiles {
        let h = fb[3] - fb[2];
        if n == 0 || n > h {
            bail!("--tiles {n}: the film has {h} rows of pixels (strips of at least one row)");
        }
        for i in 0..n {
            let (y0, y1) = (fb[2] + i * h / n, fb[2] + (i + 1) * h / n);
            let bounds = [fb[0], fb[1], y0, y1].map(|v| v.to_string()).to_vec();
            let mut extra = vec!["--seed".to_string(), seed.to_string(), "--pixelbounds".into()];
            extra.extend(bounds);
            push(format!("tile-{i:03}.exr"), extra);
        }
        "tiles"
    } else if let Some(k) = args.seeds {
        if k == 0 {
            bail!("--seeds must be at least 1");
        }
        for i in 0..k {
            push(format!("seed-{i:03}.exr"), vec!["--seed".into(), seed.wrapping_add(i as i32).to_string()]);
        }
        "seeds"
    } else {
        let file = args.cameras.as_ref().expect("one split was given");
        for (i, c) in read_cameras(file)?.iter().enumerate() {
            let mut extra = vec!["--seed".to_string(), seed.to_string(), "--lookat".into()];
            extra.extend(c.iter().map(|v| v.to_string()));
            push(format!("frame-{i:03}.exr"), extra);
        }
        "cameras"
    };
    Ok(Manifest {
        scene: scene_abs,
        scene_hash: super::scene_hash::of_file(scene)?,
        mode: mode.into(),
        precompute,
        tasks,
        cpus_per_task: args.cpus_per_task.max(1),
        sbatch_options: args.sbatch_options.clone(),
    })
}

/// A task's command as one shell line: written under a temporary name, renamed when complete.
fn task_line(t: &Task, dir: &Path) -> String {
    let out = dir.join(&t.output);
    let tmp = dir.join(format!("{}.partial.exr", t.output.trim_end_matches(".exr")));
    let mut args = t.command.clone();
    let render = args.get(1).is_some_and(|a| a == "render");
    if render && let Some(i) = args.iter().position(|a| a == "--outfile") {
        args[i + 1] = tmp.display().to_string();
        return format!(
            "{} && mv {} {}",
            shell_line(&args),
            shell_quote(&tmp.display().to_string()),
            shell_quote(&out.display().to_string())
        );
    }
    shell_line(&args)
}

fn header(m: &Manifest, dir: &Path, name: &str, log: &str) -> String {
    let stem = m.scene.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    let mut s = format!(
        "#!/bin/bash\n# Written by `nimbus cluster` ({} of {}); edit freely before submitting.\n\
         #SBATCH --job-name=nimbus-{name}-{stem}\n#SBATCH --cpus-per-task={}\n#SBATCH --output={}\n",
        m.mode,
        m.scene.display(),
        m.cpus_per_task,
        dir.join("logs").join(log).display()
    );
    for o in &m.sbatch_options {
        let _ = writeln!(s, "#SBATCH {o}");
    }
    s
}

/// `0-3`, `1,4-6`: the array indices in sbatch's syntax.
pub fn array_spec(indices: &[usize]) -> String {
    let mut parts: Vec<String> = Vec::new();
    let mut i = 0;
    while i < indices.len() {
        let mut j = i;
        while j + 1 < indices.len() && indices[j + 1] == indices[j] + 1 {
            j += 1;
        }
        parts.push(if i == j { indices[i].to_string() } else { format!("{}-{}", indices[i], indices[j]) });
        i = j + 1;
    }
    parts.join(",")
}

/// The array job over `indices` of the manifest's tasks.
fn render_script(m: &Manifest, dir: &Path, indices: &[usize]) -> String {
    let mut s = header(m, dir, "render", "render-%a.log");
    let _ = write!(
        s,
        "#SBATCH --array={}\nset -euo pipefail\n# Task i runs line i+1 of tasks.txt: the exact nimbus command.\n\
         cmd=$(sed -n \"$((SLURM_ARRAY_TASK_ID + 1))p\" {})\necho \"$cmd\"\neval \"$cmd\"\n",
        array_spec(indices),
        shell_quote(&dir.join("tasks.txt").display().to_string())
    );
    s
}

fn precompute_script(m: &Manifest, dir: &Path, task: &Task) -> String {
    let mut s = header(m, dir, "precompute", "precompute.log");
    let _ = writeln!(s, "set -euo pipefail\n{}", shell_line(&task.command));
    s
}

fn write_file(path: &Path, text: &str, executable: bool) -> Result<()> {
    std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))?;
    #[cfg(unix)]
    if executable {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755))
            .with_context(|| format!("making {} executable", path.display()))?;
    }
    Ok(())
}

/// `sbatch --parsable [dependency] script`: the job id.
fn sbatch(script: &Path, after: Option<&str>) -> Result<String> {
    let mut cmd = Command::new("sbatch");
    cmd.arg("--parsable");
    if let Some(id) = after {
        cmd.arg(format!("--dependency=afterok:{id}"));
    }
    let out = cmd.arg(script).output().map_err(|e| {
        anyhow::anyhow!("cannot run sbatch ({e}): is Slurm installed here? The scripts are in {}", script.display())
    })?;
    if !out.status.success() {
        bail!("sbatch {} failed: {}", script.display(), String::from_utf8_lossy(&out.stderr).trim());
    }
    let text = String::from_utf8_lossy(&out.stdout);
    // `--parsable` prints "id" or "id;cluster".
    Ok(text.trim().split(';').next().unwrap_or("").to_string())
}

/// The scripts for `indices` (with the precomputation first when `with_precompute`), written
/// to `dir`, and submitted when `submit`. Returns the `submit.sh` text.
fn write_and_submit(
    m: &Manifest,
    dir: &Path,
    indices: &[usize],
    with_precompute: bool,
    script: &str,
    submit: bool,
) -> Result<()> {
    let array = dir.join(script);
    write_file(&array, &render_script(m, dir, indices), false)?;
    let pre = match (&m.precompute, with_precompute) {
        (Some(task), true) => {
            let path = dir.join("precompute.sbatch");
            write_file(&path, &precompute_script(m, dir, task), false)?;
            Some(path)
        }
        _ => None,
    };
    let mut sh = String::from("#!/bin/bash\n# What `nimbus cluster --submit` runs.\nset -euo pipefail\n");
    match &pre {
        Some(p) => {
            let _ = writeln!(sh, "pre=$(sbatch --parsable {})", shell_quote(&p.display().to_string()));
            let _ = writeln!(
                sh,
                "sbatch --parsable --dependency=afterok:\"${{pre%%;*}}\" {}",
                shell_quote(&array.display().to_string())
            );
        }
        None => {
            let _ = writeln!(sh, "sbatch --parsable {}", shell_quote(&array.display().to_string()));
        }
    }
    let name = if script == "render.sbatch" { "submit.sh".to_string() } else { "resubmit.sh".to_string() };
    write_file(&dir.join(&name), &sh, true)?;
    if submit {
        let pre_id = pre.as_ref().map(|p| sbatch(p, None)).transpose()?;
        let id = sbatch(&array, pre_id.as_deref())?;
        if let Some(p) = &pre_id {
            println!("precompute job {p}");
        }
        println!("array job {id} ({} tasks)", indices.len());
        let mut jobs = std::fs::read_to_string(dir.join("jobs.txt")).unwrap_or_default();
        if let Some(p) = &pre_id {
            let _ = writeln!(jobs, "precompute {p}");
        }
        let _ = writeln!(jobs, "array {id} {}", array_spec(indices));
        write_file(&dir.join("jobs.txt"), &jobs, false)?;
    } else {
        eprintln!("wrote {}; submit with `bash {}`", dir.display(), dir.join(&name).display());
    }
    Ok(())
}

fn new_split(args: &ClusterArgs) -> Result<ExitCode> {
    let scene = args.scene.as_ref().expect("clap requires the scene");
    let out = args.out.as_ref().expect("clap requires --out");
    if args.cpus_per_task == 0 {
        bail!("--cpus-per-task must be at least 1");
    }
    let m = plan(args, scene, out)?;
    let dir = absolute(out)?;
    std::fs::create_dir_all(dir.join("logs")).with_context(|| format!("creating {}", dir.display()))?;
    if dir.join("cluster.json").exists() {
        bail!("{} already holds a split (cluster.json): use --resume {0} or another --out", dir.display());
    }
    let lines: String = m.tasks.iter().map(|t| task_line(t, &dir) + "\n").collect();
    write_file(&dir.join("tasks.txt"), &lines, false)?;
    m.write(&dir.join("cluster.json"))?;
    let all: Vec<usize> = (0..m.tasks.len()).collect();
    write_and_submit(&m, &dir, &all, true, "render.sbatch", args.submit)?;
    Ok(ExitCode::SUCCESS)
}

/// The indices of the tasks whose parts are not in `dir`.
pub fn missing_tasks(m: &Manifest, dir: &Path) -> Vec<usize> {
    (0..m.tasks.len()).filter(|&i| !dir.join(&m.tasks[i].output).exists()).collect()
}

fn resume(args: &ClusterArgs, dir: &Path) -> Result<ExitCode> {
    let dir = absolute(dir)?;
    let m = Manifest::read(&dir.join("cluster.json"))?;
    let now = super::scene_hash::of_file(&m.scene)?;
    if now != m.scene_hash {
        bail!(
            "{} changed since the split was made (hash {now}, was {}): its parts would not merge; make a new split",
            m.scene.display(),
            m.scene_hash
        );
    }
    let missing = missing_tasks(&m, &dir);
    if missing.is_empty() {
        println!("all {} parts are in {}: nothing to resubmit", m.tasks.len(), dir.display());
        return Ok(ExitCode::SUCCESS);
    }
    let names: Vec<&str> = missing.iter().map(|&i| m.tasks[i].output.as_str()).collect();
    println!("{} of {} parts missing: {}", missing.len(), m.tasks.len(), names.join(", "));
    let pre_missing = m.precompute.as_ref().is_some_and(|p| !dir.join(&p.output).exists());
    write_and_submit(&m, &dir, &missing, pre_missing, "resume.sbatch", args.submit)?;
    Ok(ExitCode::SUCCESS)
}

/// Runs the command.
pub fn run(args: &ClusterArgs) -> Result<ExitCode> {
    match &args.resume {
        Some(dir) => resume(args, dir),
        None => new_split(args),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn array_specs_compress_runs() {
        assert_eq!(array_spec(&[0, 1, 2, 3]), "0-3");
        assert_eq!(array_spec(&[1, 4, 5, 6, 9]), "1,4-6,9");
        assert_eq!(array_spec(&[7]), "7");
    }

    #[test]
    fn shell_quoting_survives_spaces_and_quotes() {
        assert_eq!(shell_quote("/a/b.pbrt"), "/a/b.pbrt");
        assert_eq!(shell_quote("my scene.pbrt"), "'my scene.pbrt'");
        assert_eq!(shell_quote("it's"), "'it'\\''s'");
        assert_eq!(shell_quote(""), "''");
    }

    #[test]
    fn manifests_round_trip() {
        let m = Manifest {
            scene: "/s/scene.pbrt".into(),
            scene_hash: "00ff".into(),
            mode: "tiles".into(),
            precompute: Some(Task { output: "graph/g_d10.txt".into(), command: vec!["nimbus".into(), "graph".into()] }),
            tasks: vec![Task { output: "tile-000.exr".into(), command: vec!["nimbus".into(), "render".into()] }],
            cpus_per_task: 2,
            sbatch_options: vec!["--partition=long".into()],
        };
        let dir = std::env::temp_dir().join(format!("nimbus-manifest-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        m.write(&dir.join("cluster.json")).unwrap();
        assert_eq!(Manifest::read(&dir.join("cluster.json")).unwrap(), m);
        std::fs::write(dir.join("bad.json"), "{\"version\": 2}").unwrap();
        assert!(Manifest::read(&dir.join("bad.json")).unwrap_err().to_string().contains("version 2"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
