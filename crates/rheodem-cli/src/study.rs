//! `rheodem study`: run a study here, or on a Slurm cluster, follow its progress, gather
//! its points into its database, and report on it (docs/studies.md).

use crate::shear::sweep_dirs;
use anyhow::{Context, Result, bail};
use rheodem::io::atomic::write_atomic;
use rheodem::run::RunError;
use rheodem::setups::registry::{SetUpInfo, study_points};
use rheodem::setups::results_db::ResultsDb;
use rheodem::setups::runner::{Event, Finished, RunOptions};
use rheodem::setups::schema::Values;
use rheodem::setups::slurm::{self, SUBMISSION_FILE, SlurmOptions, Submission};
use rheodem::setups::studied;
use rheodem::setups::study::StudySpec;
use rheodem::setups::sweep::PointStatus;
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
    /// Archive every finished point of the study not archived yet and store every one in
    /// its database (what the collect job of a cluster submission does).
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

/// A study file read for one variant, with the points of its set-up.
struct Loaded {
    /// The study file, absolute.
    file: PathBuf,
    /// The study.
    study: StudySpec,
    /// The variant's name (the file's stem, `-quick` for the quick variant).
    name: String,
    /// Whether this is the quick variant.
    quick: bool,
    /// The registered set-up of its points.
    setup: &'static SetUpInfo,
    /// The variant's points: name and spec table.
    points: Vec<(String, toml::Table)>,
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
        let (setup, points) =
            study_points(&study, quick).map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
        let sweep = study
            .variant(quick)
            .map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
        let stem = file
            .file_stem()
            .map_or("study".into(), |s| s.to_string_lossy().into_owned());
        let (out, archive) = sweep_dirs(&sweep, &file);
        Ok(Loaded {
            study,
            name: if quick { format!("{stem}-quick") } else { stem },
            quick,
            setup,
            points,
            out,
            archive,
            file,
        })
    }

    /// The study's database file, if it has one.
    fn database(&self) -> Option<PathBuf> {
        let here = self.file.parent().unwrap_or(Path::new(""));
        self.study
            .database
            .as_ref()
            .map(|d| crate::shear::beside(here, d))
    }

    /// The points' names, in order.
    fn names(&self) -> Vec<&str> {
        self.points.iter().map(|(n, _)| n.as_str()).collect()
    }

    /// The status of the point `name` (spec table `table`); a finished point gives its
    /// result file.
    fn point_status(&self, name: &str, table: &toml::Table) -> PointStatus<PathBuf> {
        (self.setup.study.status)(table, name, &self.out.join(name), self.archive.as_deref())
    }

    /// Every point's status.
    fn status(&self) -> Vec<PointStatus<PathBuf>> {
        self.points
            .iter()
            .map(|(name, table)| self.point_status(name, table))
            .collect()
    }

    /// The finished points: name and result file.
    fn finished(&self) -> Vec<(String, PathBuf)> {
        studied::finished(&self.points, &self.status())
    }

    /// Archives the finished point `name` (unless its result is the archive's already)
    /// and stores it in the database `db`.
    fn keep(&self, name: &str, result: &Path, db: Option<&mut ResultsDb>) -> Result<()> {
        if let Some(a) = &self.archive
            && !result.starts_with(a)
        {
            (self.setup.study.archive)(a, name, result).map_err(|e| anyhow::anyhow!(e))?;
        }
        if let Some(db) = db {
            (self.setup.study.store)(db, &self.name, name, result)
                .map_err(|e| anyhow::anyhow!(e))?;
        }
        Ok(())
    }
}

/// Runs (or resumes) the point `name` (spec table `table`) of `s` in its directory with
/// `threads` threads of the current pool, through the registry as `rheodem <set-up>`
/// would; returns its result file and what the run says of itself (its report and
/// warnings). Progress goes to standard error every 10 % unless `quiet`.
fn run_point(
    s: &Loaded,
    name: &str,
    table: &toml::Table,
    threads: usize,
    quiet: bool,
) -> Result<(PathBuf, Finished), RunError> {
    let dir = s.out.join(name);
    let options = RunOptions {
        dir: &dir,
        threads,
        force: false,
        from: None,
        max_memory: None,
    };
    let mut last = (None, 0);
    let finished = (s.setup.run)(table.clone(), &Values::new(), &options, &mut |e| {
        if let Event::Progress(p) = e {
            let pct = p.done * 100 / p.total.max(1);
            if !quiet && (last.0 != Some(p.stage) || pct >= last.1 + 10) {
                last = (Some(p.stage), pct);
                eprintln!("  {name}: {} {pct} %", p.stage);
            }
        }
    })?;
    match s.point_status(name, table) {
        PointStatus::Finished(file) => Ok((file, finished)),
        other => Err(RunError::OtherCommand(format!(
            "{name} ran to its end but is not finished ({other})"
        ))),
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
        } => run_points(&Loaded::new(&file, quick)?, jobs, quiet),
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
    let total = s.names().len();
    let variant = if s.quick { "quick" } else { "full" };
    let finished = s.finished();
    let done = finished.len();
    let report = (s.setup.study.report)(&s.study, variant, total, &finished);
    let report =
        report.map_err(|e| anyhow::anyhow!("cannot build the report of {}: {e}", s.name))?;
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
        "report of {} ({done} of {total} points finished) in {}",
        s.name,
        dir.display()
    );
    Ok(())
}

/// Runs (or resumes) the point `name` of the study with `threads` threads, then archives
/// it and prints its outcome (what a cluster's array task does).
fn run_one(s: &Loaded, name: &str, threads: usize) -> Result<()> {
    let table = studied::point(&s.points, name).ok_or_else(|| {
        anyhow::anyhow!(
            "{} has no point named {name:?} (`rheodem study status {} --points` lists them)",
            s.file.display(),
            s.file.display()
        )
    })?;
    // A finished point is not opened again: archived if it is not yet.
    if let PointStatus::Finished(result) = s.point_status(name, table) {
        s.keep(name, &result, None)?;
        println!("{name}: finished already");
        println!("{}", (s.setup.study.outcome)(name, &result));
        return Ok(());
    }
    let (pool, n) = crate::pool(Some(threads))?;
    match pool.install(|| run_point(s, name, table, n, false)) {
        Ok((result, finished)) => {
            s.keep(name, &result, None)?;
            print!("{}", finished.report);
            for w in &finished.warnings {
                eprintln!("warning: {w}");
            }
            println!("{}", (s.setup.study.outcome)(name, &result));
            Ok(())
        }
        Err(RunError::Busy(_)) => {
            println!("{name}: being run by another process; left to it");
            Ok(())
        }
        Err(e) => bail!("{}", in_study(e)),
    }
}

/// A point's run error as a study says it: a directory of other settings is replaced by
/// removing it (a study has no `--force`).
fn in_study(e: RunError) -> String {
    match e {
        RunError::Changed { dir, changes } => format!(
            "{} holds a run with other settings than the study's point ({}): remove the \
             directory to run the point with the study's settings",
            dir.display(),
            changes.join("; ")
        ),
        other => other.to_string(),
    }
}

/// Runs the study's missing points, `jobs` at a time with one thread each; each finished
/// point is archived and stored in the study's database at once.
fn run_points(s: &Loaded, jobs: Option<usize>, quiet: bool) -> Result<()> {
    let jobs = crate::worker_count(
        "--jobs",
        jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
    )?;
    std::fs::create_dir_all(&s.out)
        .with_context(|| format!("cannot create {}", s.out.display()))?;
    let mut todo: Vec<&(String, toml::Table)> = Vec::new();
    let mut done: Vec<(&str, PathBuf)> = Vec::new();
    for point in &s.points {
        match s.point_status(&point.0, &point.1) {
            PointStatus::Finished(result) => done.push((&point.0, result)),
            _ => todo.push(point),
        }
    }
    eprintln!(
        "{} {} points, {} to run, {jobs} at a time → {}",
        s.points.len(),
        s.setup.name,
        todo.len(),
        s.out.display()
    );
    let database = s
        .database()
        .map(|db| ResultsDb::open(&db))
        .transpose()?
        .map(std::sync::Mutex::new);
    let errors = std::sync::Mutex::new(Vec::new());
    let fail = |name: &str, e: String| {
        errors
            .lock()
            .map(|mut v| v.push(format!("{name}: {e}")))
            .ok();
    };
    // Points finished before (by an earlier run killed before it kept them, or by a
    // cluster task) are archived if they are not yet, and stored (again) in the database.
    for (name, result) in &done {
        let kept = match &database {
            Some(d) => match d.lock() {
                Ok(mut db) => s.keep(name, result, Some(&mut db)),
                Err(_) => Err(anyhow::anyhow!("database lock poisoned")),
            },
            None => s.keep(name, result, None),
        };
        if let Err(e) = kept {
            fail(name, format!("{e:#}"));
        }
    }
    let pool_errors = crate::for_each_point(todo.len(), jobs, |k, pool| {
        let (name, table) = todo[k];
        match pool.install(|| run_point(s, name, table, 1, quiet)) {
            Ok((result, _)) => {
                // One point at a time keeps the archive and the database.
                let kept = match &database {
                    Some(d) => match d.lock() {
                        Ok(mut db) => s.keep(name, &result, Some(&mut db)),
                        Err(_) => Err(anyhow::anyhow!("database lock poisoned")),
                    },
                    None => s.keep(name, &result, None),
                };
                match kept {
                    Ok(()) if !quiet => println!("{}", (s.setup.study.outcome)(name, &result)),
                    Ok(()) => {}
                    Err(e) => fail(name, format!("{e:#}")),
                }
            }
            Err(RunError::Busy(_)) => {
                if !quiet {
                    eprintln!("  {name}: being run by another process; skipped");
                }
            }
            Err(e) => fail(name, in_study(e)),
        }
    });
    errors.lock().map(|mut v| v.extend(pool_errors)).ok();
    println!(
        "{} of {} points finished",
        s.finished().len(),
        s.points.len()
    );
    let errors = errors.into_inner().unwrap_or_default();
    if !errors.is_empty() {
        bail!("{} errors:\n{}", errors.len(), errors.join("\n"));
    }
    Ok(())
}

/// Archives and stores in the study's database every finished point (what the collect
/// job of a cluster submission does).
fn collect(s: &Loaded) -> Result<()> {
    let finished = s.finished();
    let mut database = s.database().map(|db| ResultsDb::open(&db)).transpose()?;
    for (name, result) in &finished {
        s.keep(name, result, database.as_mut())?;
    }
    match (&database, s.database()) {
        (Some(db), Some(file)) => println!(
            "{} of {} points finished; {} stored under study {:?} in {}",
            finished.len(),
            s.points.len(),
            db.count_runs(s.setup.name, Some(&s.name))?,
            s.name,
            file.display()
        ),
        _ => println!(
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
        .names()
        .into_iter()
        .zip(&status)
        .filter(|(name, st)| {
            !matches!(st, PointStatus::Finished(_) | PointStatus::Running(_))
                && !queued.iter().any(|q| q == name)
        })
        .map(|(name, _)| name)
        .collect();
    if missing.is_empty() {
        println!(
            "{}: nothing to submit ({} of {} points finished, the rest running or queued)",
            s.name,
            status
                .iter()
                .filter(|st| matches!(st, PointStatus::Finished(_)))
                .count(),
            status.len()
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
    let count = |f: fn(&PointStatus<PathBuf>) -> bool| status.iter().filter(|st| f(st)).count();
    let finished = count(|s| matches!(s, PointStatus::Finished(_)));
    println!("{}: {finished} of {} points finished", s.name, status.len());
    println!(
        "  running {}, stopped {}, failed {}, not started {}",
        count(|s| matches!(s, PointStatus::Running(_))),
        count(|s| matches!(s, PointStatus::Stopped(_))),
        count(|s| matches!(s, PointStatus::Failed(..))),
        count(|s| matches!(s, PointStatus::Waiting))
    );
    for (name, st) in s.names().into_iter().zip(&status) {
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
        let collecting = slurm::queue(&sub.collect_job).unwrap_or_default();
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
        let database = ResultsDb::open(&db)?;
        let stored = database.count_runs(s.setup.name, Some(&s.name))?;
        println!("  database {}: {stored} points of {}", db.display(), s.name);
    }
    Ok(())
}
