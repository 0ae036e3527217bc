//! Studies on a Slurm cluster (docs/studies.md §6): the missing points of a study are
//! submitted as one job array, one point per array task, followed by a collect job that
//! runs once every task has ended (`afterany`) and stores the finished points in the
//! study's results database.
//!
//! Each task runs `rheodem study run-point STUDY --point NAME`, which resumes the point
//! from its checkpoint if an earlier task was killed, skips it if it is finished, and
//! leaves it alone if another process holds it; its result goes into the point's
//! directory and the study's archive. Only the collect job writes the database: SQLite's
//! write-ahead log needs shared memory that network file systems do not provide, so one
//! writer at the end is what is safe on a cluster's shared disk.
//!
//! A submission is recorded in a directory of its own under `<out>/slurm/`: the list of
//! its points (`points.txt`, line `k` for array task `k − 1`), the two job scripts (plain
//! bash with `#SBATCH` lines: they run under `bash` too, which the tests use), the tasks'
//! logs and `submission.json` with the job ids.

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Scheduler settings of a submission.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SlurmOptions {
    /// Partition (`--partition`); the cluster's default when `None`.
    pub partition: Option<String>,
    /// Time limit of one task (`--time`, Slurm's format, e.g. `12:00:00`); the
    /// partition's default when `None`.
    pub time: Option<String>,
    /// CPUs of one task (`--cpus-per-task`): the point runs with as many threads. A point
    /// is bit-identical to a local `study run` (one thread per point) only with 1.
    pub cpus_per_task: usize,
    /// Most tasks running at once (the `%` limit of `--array`); no limit when `None`.
    pub max_parallel: Option<usize>,
    /// Further `#SBATCH` options, each written as given (e.g. `--account=abc`).
    pub extra: Vec<String>,
}

/// What is wrong with a submission, or what the scheduler said.
#[derive(Debug, thiserror::Error)]
pub enum SlurmError {
    /// An option cannot be written into a job script.
    #[error("{key} = {value:?}: {reason}")]
    Option {
        /// The option.
        key: &'static str,
        /// Its value.
        value: String,
        /// Why it is refused.
        reason: &'static str,
    },
    /// A Slurm command could not be started (not installed, not on `PATH`).
    #[error(
        "cannot run `{command}`: {source}; submitting needs a Slurm client (sbatch, squeue) \
         on PATH, as on a cluster's login node"
    )]
    Missing {
        /// The command.
        command: &'static str,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// A Slurm command failed.
    #[error("`{command}` failed: {stderr}")]
    Failed {
        /// The command line.
        command: String,
        /// What it printed on standard error.
        stderr: String,
    },
}

/// A submission as recorded in its directory's `submission.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Submission {
    /// Job id of the array.
    pub array_job: String,
    /// Job id of the collect job.
    pub collect_job: String,
    /// The points, in array-task order.
    pub points: Vec<String>,
    /// Unix time of the submission (s).
    pub submitted_unix: u64,
    /// rheodem version that submitted it.
    pub version: String,
}

/// File of a submission's directory that holds its [`Submission`].
pub const SUBMISSION_FILE: &str = "submission.json";

/// A string as one shell word (single-quoted).
pub fn shell_quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// A value that goes into an `#SBATCH` line, which Slurm splits at white space and does
/// not unquote.
fn directive_value(key: &'static str, value: &str) -> Result<String, SlurmError> {
    if value.is_empty() || value.chars().any(|c| c.is_whitespace() || c == '#') {
        return Err(SlurmError::Option {
            key,
            value: value.to_string(),
            reason: "must be non-empty, without white space or '#' (an #SBATCH line cannot \
                     quote it)",
        });
    }
    Ok(value.to_string())
}

/// The `#SBATCH` lines shared by both scripts.
fn common_directives(
    opts: &SlurmOptions,
    job_name: &str,
    cpus: usize,
) -> Result<String, SlurmError> {
    let mut s = format!(
        "#SBATCH --job-name={}\n#SBATCH --ntasks=1\n#SBATCH --cpus-per-task={cpus}\n",
        directive_value("job name", job_name)?
    );
    if let Some(p) = &opts.partition {
        s += &format!(
            "#SBATCH --partition={}\n",
            directive_value("--partition", p)?
        );
    }
    if let Some(t) = &opts.time {
        s += &format!("#SBATCH --time={}\n", directive_value("--time", t)?);
    }
    for e in &opts.extra {
        let e = directive_value("--sbatch-arg", e)?;
        if !e.starts_with('-') {
            return Err(SlurmError::Option {
                key: "--sbatch-arg",
                value: e,
                reason: "must be an sbatch option (starting with '-')",
            });
        }
        s += &format!("#SBATCH {e}\n");
    }
    Ok(s)
}

/// The command that runs rheodem on the study: `rheodem study SUB STUDY [--quick]`.
fn study_command(rheodem: &Path, sub: &str, study: &Path, quick: bool) -> String {
    format!(
        "{} study {sub} {}{}",
        shell_quote(&rheodem.to_string_lossy()),
        shell_quote(&study.to_string_lossy()),
        if quick { " --quick" } else { "" }
    )
}

/// The job array's script: task `k` runs the point on line `k + 1` of `list`, with
/// `opts.cpus_per_task` threads, logging to `dir/task-<k>.out`. Paths should be absolute
/// (the tasks start in `dir`).
pub fn array_script(
    opts: &SlurmOptions,
    job_name: &str,
    rheodem: &Path,
    study: &Path,
    quick: bool,
    dir: &Path,
    tasks: usize,
) -> Result<String, SlurmError> {
    if opts.cpus_per_task == 0 {
        return Err(SlurmError::Option {
            key: "--cpus-per-task",
            value: "0".into(),
            reason: "must be at least 1",
        });
    }
    if tasks == 0 {
        return Err(SlurmError::Option {
            key: "points",
            value: "0".into(),
            reason: "a job array needs at least one point",
        });
    }
    let limit = match opts.max_parallel {
        Some(0) => {
            return Err(SlurmError::Option {
                key: "--max-parallel",
                value: "0".into(),
                reason: "must be at least 1",
            });
        }
        Some(m) => format!("%{m}"),
        None => String::new(),
    };
    let d = directive_value("submission directory", &dir.to_string_lossy())?;
    let list = shell_quote(&dir.join("points.txt").to_string_lossy());
    Ok(format!(
        "#!/bin/bash\n{}#SBATCH --array=0-{}{limit}\n#SBATCH --chdir={d}\n\
         #SBATCH --output={d}/task-%a.out\n\
         # Written by rheodem {}: one point of the study per array task. A task resumes its\n\
         # point from the last checkpoint, so this script can be submitted again as it is.\n\
         set -euo pipefail\n\
         point=$(sed -n \"$((SLURM_ARRAY_TASK_ID + 1))p\" {list})\n\
         exec {} --point \"$point\" --threads {}\n",
        common_directives(opts, job_name, opts.cpus_per_task)?,
        tasks - 1,
        crate::VERSION,
        study_command(rheodem, "run-point", study, quick),
        opts.cpus_per_task
    ))
}

/// The collect job's script: stores every finished point of the study in its database
/// and refreshes its archive's table, logging to `dir/collect.out`.
pub fn collect_script(
    opts: &SlurmOptions,
    job_name: &str,
    rheodem: &Path,
    study: &Path,
    quick: bool,
    dir: &Path,
) -> Result<String, SlurmError> {
    let d = directive_value("submission directory", &dir.to_string_lossy())?;
    Ok(format!(
        "#!/bin/bash\n{}#SBATCH --chdir={d}\n#SBATCH --output={d}/collect.out\n\
         # Written by rheodem {}: gathers the study's finished points into its database.\n\
         set -euo pipefail\nexec {}\n",
        common_directives(opts, &format!("{job_name}-collect"), 1)?,
        crate::VERSION,
        study_command(rheodem, "collect", study, quick),
    ))
}

/// Runs a Slurm client command, returning its standard output.
fn slurm(command: &'static str, args: &[&str]) -> Result<String, SlurmError> {
    let out = Command::new(command)
        .args(args)
        .output()
        .map_err(|source| SlurmError::Missing { command, source })?;
    if !out.status.success() {
        return Err(SlurmError::Failed {
            command: format!("{command} {}", args.join(" ")),
            stderr: String::from_utf8_lossy(&out.stderr).trim().to_string(),
        });
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// Submits `script` with `sbatch --parsable`, after the job `after` has ended (in any
/// state) if given; returns the new job's id.
pub fn sbatch(script: &Path, after: Option<&str>) -> Result<String, SlurmError> {
    let dependency = after.map(|id| format!("--dependency=afterany:{id}"));
    let script = script.to_string_lossy();
    let mut args = vec!["--parsable"];
    args.extend(dependency.as_deref());
    args.push(&script);
    let out = slurm("sbatch", &args)?;
    // `--parsable` prints `id` or `id;cluster`.
    let id = out.trim().split(';').next().unwrap_or("").to_string();
    if id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
        return Err(SlurmError::Failed {
            command: format!("sbatch --parsable {script}"),
            stderr: format!("printed {:?}, not a job id", out.trim()),
        });
    }
    Ok(id)
}

/// The state of a job's tasks in the queue (`PENDING`, `RUNNING`, …), from `squeue`: one
/// entry per array task (`Some(k)`) or for the job itself (`None`). A job that has left
/// the queue has no entries.
pub fn queue(job: &str) -> Result<Vec<(Option<usize>, String)>, SlurmError> {
    // An unknown (finished, purged) job id is an error for squeue; listing every job of
    // the queue and filtering is the same answer without it.
    let out = slurm("squeue", &["-h", "-r", "-o", "%i %T"])?;
    Ok(parse_queue(&out, job))
}

/// The entries of `job` in `squeue -h -r -o "%i %T"` output.
fn parse_queue(out: &str, job: &str) -> Vec<(Option<usize>, String)> {
    out.lines()
        .filter_map(|line| {
            let (id, state) = line.trim().split_once(' ')?;
            let (base, task) = match id.split_once('_') {
                Some((b, t)) => (b, t.parse().ok()),
                None => (id, None),
            };
            (base == job).then(|| (task, state.trim().to_string()))
        })
        .collect()
}

/// Reads every submission recorded under `slurm_dir` (each `*/submission.json`), oldest
/// first, with its directory.
pub fn submissions(slurm_dir: &Path) -> Vec<(PathBuf, Submission)> {
    let Ok(entries) = std::fs::read_dir(slurm_dir) else {
        return Vec::new();
    };
    let mut found: Vec<(PathBuf, Submission)> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter_map(|d| {
            let text = std::fs::read_to_string(d.join(SUBMISSION_FILE)).ok()?;
            Some((d, serde_json::from_str(&text).ok()?))
        })
        .collect();
    found.sort_by_key(|(d, s)| (s.submitted_unix, d.clone()));
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts() -> SlurmOptions {
        SlurmOptions {
            partition: Some("short".into()),
            time: Some("01:00:00".into()),
            cpus_per_task: 2,
            max_parallel: Some(4),
            extra: vec!["--account=granular".into()],
        }
    }

    #[test]
    fn the_array_script_names_every_option_and_quotes_paths() {
        let s = array_script(
            &opts(),
            "rheodem-pd",
            Path::new("/opt/it's/rheodem"),
            Path::new("/home/a/pd.toml"),
            true,
            Path::new("/scratch/pd/slurm/1"),
            3,
        )
        .expect("script");
        for line in [
            "#SBATCH --array=0-2%4",
            "#SBATCH --partition=short",
            "#SBATCH --time=01:00:00",
            "#SBATCH --cpus-per-task=2",
            "#SBATCH --account=granular",
            "#SBATCH --output=/scratch/pd/slurm/1/task-%a.out",
            "point=$(sed -n \"$((SLURM_ARRAY_TASK_ID + 1))p\" '/scratch/pd/slurm/1/points.txt')",
            "exec '/opt/it'\\''s/rheodem' study run-point '/home/a/pd.toml' --quick --point \"$point\" --threads 2",
        ] {
            assert!(s.lines().any(|l| l == line), "{line} not in\n{s}");
        }
        assert!(s.starts_with("#!/bin/bash\n"));
        let c = collect_script(
            &opts(),
            "rheodem-pd",
            Path::new("/r"),
            Path::new("/s.toml"),
            false,
            Path::new("/d"),
        )
        .expect("collect");
        assert!(c.contains("#SBATCH --job-name=rheodem-pd-collect\n"));
        assert!(c.contains("#SBATCH --cpus-per-task=1\n"));
        assert!(c.ends_with("exec '/r' study collect '/s.toml'\n"), "{c}");
    }

    #[test]
    fn options_a_script_cannot_hold_are_refused_by_name() {
        let run = |o: &SlurmOptions, dir: &str, n| {
            array_script(
                o,
                "j",
                Path::new("/r"),
                Path::new("/s"),
                false,
                Path::new(dir),
                n,
            )
            .expect_err("refused")
            .to_string()
        };
        let mut o = opts();
        o.partition = Some("two words".into());
        assert!(run(&o, "/d", 1).starts_with("--partition = \"two words\""));
        let mut o = opts();
        o.cpus_per_task = 0;
        assert!(run(&o, "/d", 1).contains("--cpus-per-task"));
        let mut o = opts();
        o.max_parallel = Some(0);
        assert!(run(&o, "/d", 1).contains("--max-parallel"));
        let mut o = opts();
        o.extra = vec!["account=x".into()];
        assert!(run(&o, "/d", 1).contains("starting with '-'"));
        assert!(run(&opts(), "/my runs", 1).contains("submission directory"));
        assert!(run(&opts(), "/d", 0).contains("at least one point"));
    }

    #[test]
    fn the_queue_is_read_per_task() {
        let out = "12_0 RUNNING\n12_2 PENDING\n13 PENDING\n120_1 RUNNING\n";
        assert_eq!(
            parse_queue(out, "12"),
            vec![(Some(0), "RUNNING".into()), (Some(2), "PENDING".into())]
        );
        assert_eq!(parse_queue(out, "13"), vec![(None, "PENDING".into())]);
        assert!(parse_queue(out, "14").is_empty());
    }

    #[test]
    fn a_missing_client_is_named() {
        let e = slurm("rheodem-no-such-sbatch", &[]).expect_err("missing");
        assert!(e.to_string().contains("needs a Slurm client"), "{e}");
    }
}
