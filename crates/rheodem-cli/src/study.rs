//! `rheodem study`: run a study here, or on a Slurm cluster, follow its progress, gather
//! its points into its database, and report on it (docs/studies.md).

use crate::shear::{report as report_point, run_sweep, sweep_dirs};
use anyhow::{Context, Result, bail};
use rheodem::io::atomic::write_atomic;
use rheodem::run::RunError;
use rheodem::setups::archive::{archive_point, refresh_table};
use rheodem::setups::results_db::ResultsDb;
use rheodem::setups::slurm::{self, SUBMISSION_FILE, SlurmOptions, Submission};
use rheodem::setups::study::StudySpec;
use rheodem::setups::sweep::{
    PointResult, PointStatus, SweepSpec, expand, run_point, sweep_status,
};
use std::path::{Path, PathBuf};

/// The `study` subcommands (docs/studies.md).
#[derive(clap::Subcommand)]
pub enum StudyCommand {
    /// Run the study's missing points (finished ones are never rerun; a killed study
    /// resumes where it stopped).
    Run {
        /// The study file (TOML).
        file: PathBuf,
        /// Run the quick variant (fewer points, smaller systems).
        #[arg(long)]
        quick: bool,
        /// Points run at once (one thread each; default: all logical CPUs).
        #[arg(long, short)]
        jobs: Option<usize>,
        /// Less output.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Submit the study's missing points to a Slurm cluster as one job array (one point
    /// per task), followed by a job that gathers them into the study's database.
    Submit {
        /// The study file (TOML).
        file: PathBuf,
        /// The quick variant.
        #[arg(long)]
        quick: bool,
        /// Submit with Slurm's sbatch (the scheduler supported).
        #[arg(long, required = true)]
        slurm: bool,
        /// Partition of the jobs (default: the cluster's).
        #[arg(long)]
        partition: Option<String>,
        /// Time limit of one task, in Slurm's format (e.g. 12:00:00); a task killed at its
        /// limit resumes from its checkpoint when the study is submitted again.
        #[arg(long)]
        time: Option<String>,
        /// CPUs (threads) of one task; 1 gives results bit-identical to `study run`.
        #[arg(long, default_value_t = 1)]
        cpus_per_task: usize,
        /// Most tasks running at once (default: no limit).
        #[arg(long)]
        max_parallel: Option<usize>,
        /// A further sbatch option for both jobs (repeatable), e.g. --sbatch-arg=--account=abc.
        #[arg(long, allow_hyphen_values = true)]
        sbatch_arg: Vec<String>,
        /// The rheodem binary the tasks run (default: this one); it must be reachable from
        /// the compute nodes.
        #[arg(long)]
        rheodem: Option<PathBuf>,
        /// Write the job scripts and the point list, submit nothing.
        #[arg(long)]
        dry_run: bool,
    },
    /// Run one point of the study (what a cluster's array task does): resumes it from its
    /// checkpoint, archives it; skips it if finished or held by another process.
    RunPoint {
        /// The study file (TOML).
        file: PathBuf,
        /// The quick variant.
        #[arg(long)]
        quick: bool,
        /// The point's name (its directory's; `study status --points` lists them).
        #[arg(long)]
        point: String,
        /// Worker threads of the point.
        #[arg(long, default_value_t = 1)]
        threads: usize,
    },
    /// Store every finished point of the study in its database and refresh its archive's
    /// table (what the collect job of a cluster submission does).
    Collect {
        /// The study file (TOML).
        file: PathBuf,
        /// The quick variant.
        #[arg(long)]
        quick: bool,
    },
    /// Write the study's report (Markdown, and HTML with the figures embedded) from its
    /// finished points, into `<out>/report/`.
    Report {
        /// The study file (TOML).
        file: PathBuf,
        /// The quick variant.
        #[arg(long)]
        quick: bool,
    },
    /// How far the study is: finished, running, stopped and failed points, and the state
    /// of its cluster jobs in the queue.
    Status {
        /// The study file (TOML).
        file: PathBuf,
        /// The quick variant.
        #[arg(long)]
        quick: bool,
        /// List every point with its state.
        #[arg(long)]
        points: bool,
    },
}

/// A study file read with its sweep for one variant.
struct Loaded {
    /// The study file, absolute.
    file: PathBuf,
    /// The study.
    study: StudySpec,
    /// The variant's sweep.
    sweep: SweepSpec,
    /// The variant's name (the file's stem, `-quick` for the quick variant).
    name: String,
    /// Whether this is the quick variant.
    quick: bool,
    /// The variant's points.
    points: Vec<(String, rheodem::setups::shear_box::ShearBoxSpec)>,
    /// Where the points run.
    out: PathBuf,
    /// The archive of finished points, if the variant keeps one.
    archive: Option<PathBuf>,
}

impl Loaded {
    fn new(file: &Path, quick: bool) -> Result<Loaded> {
        let text = std::fs::read_to_string(file)
            .with_context(|| format!("cannot read {}", file.display()))?;
        let file = std::path::absolute(file)
            .with_context(|| format!("cannot resolve {}", file.display()))?;
        let study =
            StudySpec::from_toml(&text).map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
        let sweep = study
            .sweep(quick)
            .map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
        let stem = file
            .file_stem()
            .map_or("study".into(), |s| s.to_string_lossy().into_owned());
        let points = expand(&sweep)?;
        let (out, archive) = sweep_dirs(&sweep, &file);
        Ok(Loaded {
            study,
            sweep,
            name: if quick { format!("{stem}-quick") } else { stem },
            quick,
            points,
            out,
            archive,
            file,
        })
    }

    /// The study's database file, if it has one.
    fn database(&self) -> Option<PathBuf> {
        let here = self.file.parent().unwrap_or(Path::new(""));
        self.study.database.as_ref().map(|d| here.join(d))
    }

    /// Every point's status.
    fn status(&self) -> Vec<PointStatus> {
        sweep_status(&self.points, &self.out, self.archive.as_deref())
    }

    /// The finished points.
    fn finished(&self) -> Vec<PointResult> {
        self.status()
            .into_iter()
            .filter_map(|s| match s {
                PointStatus::Finished(r) => Some(*r),
                _ => None,
            })
            .collect()
    }
}

/// Runs a `study` subcommand.
pub fn study(cmd: StudyCommand) -> Result<()> {
    match cmd {
        StudyCommand::Run {
            file,
            quick,
            jobs,
            quiet,
        } => {
            let s = Loaded::new(&file, quick)?;
            run_sweep(
                &s.sweep,
                &s.file,
                &s.name,
                jobs,
                quiet,
                s.database().as_deref(),
            )
        }
        StudyCommand::Submit {
            file,
            quick,
            slurm: _,
            partition,
            time,
            cpus_per_task,
            max_parallel,
            sbatch_arg,
            rheodem,
            dry_run,
        } => {
            let opts = SlurmOptions {
                partition,
                time,
                cpus_per_task,
                max_parallel,
                extra: sbatch_arg,
            };
            submit(&Loaded::new(&file, quick)?, &opts, rheodem, dry_run)
        }
        StudyCommand::RunPoint {
            file,
            quick,
            point,
            threads,
        } => run_one(&Loaded::new(&file, quick)?, &point, threads),
        StudyCommand::Collect { file, quick } => collect(&Loaded::new(&file, quick)?),
        StudyCommand::Report { file, quick } => report(&Loaded::new(&file, quick)?),
        StudyCommand::Status {
            file,
            quick,
            points,
        } => status(&Loaded::new(&file, quick)?, points),
    }
}

/// Writes the study's report into `<out>/report/`.
fn report(s: &Loaded) -> Result<()> {
    let finished = s.finished();
    let total = s.points.len();
    let variant = if s.quick { "quick" } else { "full" };
    let report = rheodem::setups::study::report(&s.study, variant, total, &finished)
        .map_err(|e| anyhow::anyhow!("cannot build the report of {}: {e}", s.name))?;
    let dir = s.out.join("report");
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let write = |file: PathBuf, bytes: &[u8]| {
        write_atomic(&file, bytes).with_context(|| format!("cannot write {}", file.display()))
    };
    for f in &report.figures {
        write(dir.join(format!("{}.png", f.name)), &f.png)?;
        write(dir.join(format!("{}.svg", f.name)), f.svg.as_bytes())?;
    }
    write(dir.join("report.md"), report.markdown.as_bytes())?;
    let html = rheodem::setups::study::report_html(&report, &s.study.title);
    write(dir.join("index.html"), html.as_bytes())?;
    println!(
        "report of {} ({} of {total} points finished) in {}",
        s.name,
        finished.len(),
        dir.display()
    );
    Ok(())
}

/// Runs (or resumes) the point `name` of the study with `threads` threads.
fn run_one(s: &Loaded, name: &str, threads: usize) -> Result<()> {
    let Some((_, spec)) = s.points.iter().find(|(n, _)| n == name) else {
        bail!(
            "{} has no point named {name:?} (`rheodem study status {} --points` lists them)",
            s.file.display(),
            s.file.display()
        );
    };
    let archived = s.archive.as_deref();
    if archived.is_some_and(|a| rheodem::setups::archive::archived(a, name, spec).is_some()) {
        println!("{name}: finished already (archived)");
        return Ok(());
    }
    let (pool, n) = crate::pool(Some(threads))?;
    let dir = s.out.join(name);
    let mut last = 0;
    let outcome = pool.install(|| {
        run_point(name, spec, &dir, n, &mut |done, total| {
            let pct = done * 100 / total.max(1);
            if pct >= last + 10 {
                last = pct;
                eprintln!("  {name}: {pct} %");
            }
        })
    });
    match outcome {
        Ok(r) => {
            if let Some(a) = &s.archive {
                archive_point(a, &r)?;
            }
            report_point(&r, &dir);
            Ok(())
        }
        Err(RunError::Busy(_)) => {
            println!("{name}: being run by another process; left to it");
            Ok(())
        }
        Err(e) => Err(e.into()),
    }
}

/// Stores every finished point in the study's database and refreshes its archive's table.
fn collect(s: &Loaded) -> Result<()> {
    let finished = s.finished();
    if let Some(a) = s.archive.as_deref().filter(|a| a.is_dir()) {
        refresh_table(a)?;
    }
    match s.database() {
        Some(db) => {
            let mut database = ResultsDb::open(&db)?;
            for r in &finished {
                database.insert(&s.name, r)?;
            }
            println!(
                "{} of {} points finished; {} stored under study {:?} in {}",
                finished.len(),
                s.points.len(),
                database.count(Some(&s.name))?,
                s.name,
                db.display()
            );
        }
        None => println!(
            "{} of {} points finished; the study names no database to store them in",
            finished.len(),
            s.points.len()
        ),
    }
    Ok(())
}

/// The points of earlier submissions still in the queue (pending or running), by name.
fn queued_points(slurm_dir: &Path) -> Result<Vec<String>> {
    let mut queued = Vec::new();
    for (_, sub) in slurm::submissions(slurm_dir) {
        for (task, _) in slurm::queue(&sub.array_job)? {
            match task {
                Some(k) => queued.extend(sub.points.get(k).cloned()),
                // The whole array, not yet split into tasks.
                None => queued.extend(sub.points.iter().cloned()),
            }
        }
    }
    Ok(queued)
}

/// Submits the study's missing points to Slurm (or only writes the scripts).
fn submit(s: &Loaded, opts: &SlurmOptions, rheodem: Option<PathBuf>, dry_run: bool) -> Result<()> {
    let slurm_dir = s.out.join("slurm");
    let queued = if dry_run {
        Vec::new()
    } else {
        queued_points(&slurm_dir)?
    };
    let status = s.status();
    let missing: Vec<&str> = s
        .points
        .iter()
        .zip(&status)
        .filter(|((name, _), st)| {
            !matches!(st, PointStatus::Finished(_) | PointStatus::Running(_))
                && !queued.contains(name)
        })
        .map(|((name, _), _)| name.as_str())
        .collect();
    if missing.is_empty() {
        println!(
            "{}: nothing to submit ({} of {} points finished, the rest running or queued)",
            s.name,
            status
                .iter()
                .filter(|st| matches!(st, PointStatus::Finished(_)))
                .count(),
            s.points.len()
        );
        return Ok(());
    }
    let rheodem = match rheodem {
        Some(p) => std::path::absolute(&p)?,
        None => std::env::current_exe().context("cannot find this rheodem binary")?,
    };
    std::fs::create_dir_all(&slurm_dir)
        .with_context(|| format!("cannot create {}", slurm_dir.display()))?;
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    // A directory of its own (create_dir fails if another submission took the name).
    let dir = (0..)
        .map(|k| slurm_dir.join(format!("{now}-{k}")))
        .find(|d| std::fs::create_dir(d).is_ok())
        .context("cannot create a submission directory")?;
    let job_name = format!("rheodem-{}", s.name);
    let write = |name: &str, text: &str| -> Result<PathBuf> {
        let f = dir.join(name);
        write_atomic(&f, text.as_bytes())
            .with_context(|| format!("cannot write {}", f.display()))?;
        Ok(f)
    };
    write("points.txt", &(missing.join("\n") + "\n"))?;
    let array = write(
        "array.sh",
        &slurm::array_script(
            opts,
            &job_name,
            &rheodem,
            &s.file,
            s.quick,
            &dir,
            missing.len(),
        )?,
    )?;
    let collect = write(
        "collect.sh",
        &slurm::collect_script(opts, &job_name, &rheodem, &s.file, s.quick, &dir)?,
    )?;
    if dry_run {
        println!(
            "{} points of {} not submitted (dry run): scripts in {}",
            missing.len(),
            s.name,
            dir.display()
        );
        return Ok(());
    }
    let array_job = slurm::sbatch(&array, None)?;
    let collect_job = slurm::sbatch(&collect, Some(&array_job))?;
    let sub = Submission {
        array_job: array_job.clone(),
        collect_job: collect_job.clone(),
        points: missing.iter().map(|m| m.to_string()).collect(),
        submitted_unix: now,
        version: rheodem::VERSION.to_string(),
    };
    write(SUBMISSION_FILE, &serde_json::to_string_pretty(&sub)?)?;
    println!(
        "submitted {} points of {} as job array {array_job} (collect job {collect_job}); \
         follow it with `rheodem study status {}`",
        missing.len(),
        s.name,
        s.file.display()
    );
    Ok(())
}

/// Prints how far the study is.
fn status(s: &Loaded, list: bool) -> Result<()> {
    let status = s.status();
    let count = |f: fn(&PointStatus) -> bool| status.iter().filter(|st| f(st)).count();
    let finished = count(|s| matches!(s, PointStatus::Finished(_)));
    println!(
        "{}: {finished} of {} points finished",
        s.name,
        s.points.len()
    );
    println!(
        "  running {}, stopped {}, failed {}, not started {}",
        count(|s| matches!(s, PointStatus::Running(_))),
        count(|s| matches!(s, PointStatus::Stopped(_))),
        count(|s| matches!(s, PointStatus::Failed(..))),
        count(|s| matches!(s, PointStatus::Waiting))
    );
    for ((name, _), st) in s.points.iter().zip(&status) {
        let finished = matches!(st, PointStatus::Finished(_));
        if list || matches!(st, PointStatus::Failed(..)) || (!finished && status.len() <= 20) {
            println!("  {name}: {st}");
        }
    }
    let subs = slurm::submissions(&s.out.join("slurm"));
    for (dir, sub) in &subs {
        let tasks = match slurm::queue(&sub.array_job) {
            Ok(t) => t,
            Err(e) => {
                println!("  Slurm job {}: cannot ask the queue ({e})", sub.array_job);
                continue;
            }
        };
        let collecting = slurm::queue(&sub.collect_job)?;
        let mut states: Vec<String> = tasks.iter().map(|(_, st)| st.to_lowercase()).collect();
        states.sort();
        states.dedup_by(|a, b| a == b);
        let summary: Vec<String> = states
            .iter()
            .map(|st| {
                format!(
                    "{} {st}",
                    tasks
                        .iter()
                        .filter(|(_, t)| t.to_lowercase() == *st)
                        .count()
                )
            })
            .collect();
        println!(
            "  Slurm job {} ({} points, {}): {}{}",
            sub.array_job,
            sub.points.len(),
            dir.display(),
            if tasks.is_empty() {
                "no task in the queue".to_string()
            } else {
                summary.join(", ")
            },
            if collecting.is_empty() {
                String::new()
            } else {
                format!("; collect job {} waiting", sub.collect_job)
            }
        );
    }
    if let Some(db) = s.database().filter(|d| d.exists()) {
        println!(
            "  database {}: {} points of {}",
            db.display(),
            ResultsDb::open(&db)?.count(Some(&s.name))?,
            s.name
        );
    }
    Ok(())
}
