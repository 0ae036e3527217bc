//! `rheodem study`: run a study here, or on a Slurm cluster, follow its progress, gather
//! its points into its database, and report on it (docs/studies.md).

use crate::shear::{run_sweep, sweep_dirs};
use anyhow::{Context, Result, bail};
use rheodem::io::atomic::write_atomic;
use rheodem::run::RunError;
use rheodem::setups::archive::{archive_point, refresh_table};
use rheodem::setups::results_db::ResultsDb;
use rheodem::setups::shear_box::ShearBoxSpec;
use rheodem::setups::slurm::{self, SUBMISSION_FILE, SlurmOptions, Submission};
use rheodem::setups::split_bottom::SplitBottomSpec;
use rheodem::setups::split_bottom_study;
use rheodem::setups::study::{SetUp, StudySpec};
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

/// A status without what the finished point gave.
fn strip<R>(st: PointStatus<R>) -> PointStatus<()> {
    match st {
        PointStatus::Finished(_) => PointStatus::Finished(()),
        PointStatus::Running(x) => PointStatus::Running(x),
        PointStatus::Stopped(x) => PointStatus::Stopped(x),
        PointStatus::Failed(x, e) => PointStatus::Failed(x, e),
        PointStatus::Waiting => PointStatus::Waiting,
    }
}

/// The points of a study's variant, by set-up.
enum Points {
    /// Shear-box points.
    ShearBox(Vec<(String, ShearBoxSpec)>),
    /// Split-bottom points.
    SplitBottom(Vec<(String, SplitBottomSpec)>),
}

/// A study file read with its sweep for one variant.
struct Loaded {
    /// The study file, absolute.
    file: PathBuf,
    /// The study.
    study: StudySpec,
    /// The variant's output directory, archive and tables.
    sweep: SweepSpec,
    /// The variant's name (the file's stem, `-quick` for the quick variant).
    name: String,
    /// Whether this is the quick variant.
    quick: bool,
    /// The variant's points.
    points: Points,
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
            .variant(quick)
            .map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
        let stem = file
            .file_stem()
            .map_or("study".into(), |s| s.to_string_lossy().into_owned());
        let points = match study.setup {
            SetUp::ShearBox => Points::ShearBox(expand(&sweep)?),
            SetUp::SplitBottom => Points::SplitBottom(study.split_bottom_points(quick)?),
        };
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
        self.study
            .database
            .as_ref()
            .map(|d| crate::shear::beside(here, d))
    }

    /// The points' names, in order.
    fn names(&self) -> Vec<&str> {
        match &self.points {
            Points::ShearBox(p) => p.iter().map(|(n, _)| n.as_str()).collect(),
            Points::SplitBottom(p) => p.iter().map(|(n, _)| n.as_str()).collect(),
        }
    }

    /// Every point's status (what a finished point gave left out).
    fn status(&self) -> Vec<PointStatus<()>> {
        match &self.points {
            Points::ShearBox(p) => sweep_status(p, &self.out, self.archive.as_deref())
                .into_iter()
                .map(strip)
                .collect(),
            Points::SplitBottom(p) => self.cell_status(p).into_iter().map(strip).collect(),
        }
    }

    /// The status of split-bottom points: archived, or from their directories.
    fn cell_status(&self, points: &[(String, SplitBottomSpec)]) -> Vec<PointStatus<PathBuf>> {
        points
            .iter()
            .map(|(name, spec)| {
                match self
                    .archive
                    .as_deref()
                    .and_then(|a| split_bottom_study::archived(a, name, spec))
                {
                    Some(file) => PointStatus::Finished(file),
                    None => split_bottom_study::point_status(&self.out.join(name), spec),
                }
            })
            .collect()
    }

    /// The finished shear-box points.
    fn finished(&self) -> Vec<PointResult> {
        let Points::ShearBox(p) = &self.points else {
            return Vec::new();
        };
        sweep_status(p, &self.out, self.archive.as_deref())
            .into_iter()
            .filter_map(|s| match s {
                PointStatus::Finished(r) => Some(*r),
                _ => None,
            })
            .collect()
    }

    /// The finished split-bottom points: name and `summary.json`.
    fn finished_cells(&self) -> Vec<(String, PathBuf)> {
        let Points::SplitBottom(p) = &self.points else {
            return Vec::new();
        };
        p.iter()
            .zip(self.cell_status(p))
            .filter_map(|((name, _), st)| match st {
                PointStatus::Finished(file) => Some((name.clone(), file)),
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
            match &s.points {
                Points::ShearBox(_) => run_sweep(
                    &s.sweep,
                    &s.file,
                    &s.name,
                    jobs,
                    quiet,
                    s.database().as_deref(),
                ),
                Points::SplitBottom(points) => run_cells(&s, points, jobs, quiet),
            }
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
    let total = s.names().len();
    let variant = if s.quick { "quick" } else { "full" };
    let (report, done) = match &s.points {
        Points::ShearBox(_) => {
            let finished = s.finished();
            (
                rheodem::setups::study::report(&s.study, variant, total, &finished),
                finished.len(),
            )
        }
        Points::SplitBottom(_) => {
            let finished = s.finished_cells();
            (
                rheodem::setups::study::split_bottom_report(&s.study, variant, total, &finished),
                finished.len(),
            )
        }
    };
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

/// Runs (or resumes) the point `name` of the study with `threads` threads.
fn run_one(s: &Loaded, name: &str, threads: usize) -> Result<()> {
    let missing = || {
        anyhow::anyhow!(
            "{} has no point named {name:?} (`rheodem study status {} --points` lists them)",
            s.file.display(),
            s.file.display()
        )
    };
    let (pool, n) = crate::pool(Some(threads))?;
    let dir = s.out.join(name);
    let outcome = match &s.points {
        Points::ShearBox(points) => {
            let (_, spec) = points.iter().find(|(n, _)| n == name).ok_or_else(missing)?;
            let archive = s.archive.as_deref();
            if archive.is_some_and(|a| rheodem::setups::archive::archived(a, name, spec).is_some())
            {
                println!("{name}: finished already (archived)");
                return Ok(());
            }
            let mut last = 0;
            pool.install(|| {
                run_point(name, spec, &dir, n, &mut |done, total| {
                    let pct = done * 100 / total.max(1);
                    if pct >= last + 10 {
                        last = pct;
                        eprintln!("  {name}: {pct} %");
                    }
                })
            })
            .map(|r| {
                if let Some(a) = &s.archive {
                    archive_point(a, &r)?;
                }
                let (text, warnings) = r.report(&dir);
                print!("{text}");
                for w in warnings {
                    eprintln!("warning: {w}");
                }
                Ok::<(), anyhow::Error>(())
            })
        }
        Points::SplitBottom(points) => {
            let (_, spec) = points.iter().find(|(n, _)| n == name).ok_or_else(missing)?;
            let archive = s.archive.as_deref();
            if archive.is_some_and(|a| split_bottom_study::archived(a, name, spec).is_some()) {
                println!("{name}: finished already (archived)");
                return Ok(());
            }
            pool.install(|| run_cell(name, spec, &dir, archive))
                .map(|()| Ok(()))
        }
    };
    match outcome {
        Ok(done) => done,
        Err(RunError::Busy(_)) => {
            println!("{name}: being run by another process; left to it");
            Ok(())
        }
        Err(e) => Err(e.into()),
    }
}

/// Runs (or resumes) one split-bottom point in `dir` with the current pool, archives it
/// and prints its torque and cohesion.
fn run_cell(
    name: &str,
    spec: &SplitBottomSpec,
    dir: &Path,
    archive: Option<&Path>,
) -> Result<(), RunError> {
    let mut last = (None, 0);
    let summary = split_bottom_study::run_point(spec, dir, &mut |p| {
        let pct = p.done * 100 / p.total.max(1);
        if last.0 != Some(p.stage) || pct >= last.1 + 10 {
            last = (Some(p.stage), pct);
            eprintln!("  {name}: {} {pct} %", p.stage);
        }
    })?;
    if let Some(a) = archive {
        split_bottom_study::archive_point(a, name, &summary)?;
    }
    match rheodem::setups::wet_study::WetRun::read_summary(&summary, name) {
        Ok(r) => println!(
            "{name}: μ = {:.4} ± {:.4}, c* = {:.3} ± {:.3}, T* = {:.4e}",
            r.mu.0, r.mu.1, r.cohesion.0, r.cohesion.1, r.torque.0
        ),
        Err(e) => println!("{name}: finished ({e})"),
    }
    Ok(())
}

/// Runs the missing split-bottom points, `jobs` at a time with one thread each.
fn run_cells(
    s: &Loaded,
    points: &[(String, SplitBottomSpec)],
    jobs: Option<usize>,
    quiet: bool,
) -> Result<()> {
    let jobs = crate::worker_count(
        "--jobs",
        jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
    )?;
    std::fs::create_dir_all(&s.out)
        .with_context(|| format!("cannot create {}", s.out.display()))?;
    eprintln!(
        "{} split-bottom points, {jobs} at a time → {}",
        points.len(),
        s.out.display()
    );
    let errors = std::sync::Mutex::new(Vec::new());
    let pool_errors = crate::for_each_point(points.len(), jobs, |k, pool| {
        let (name, spec) = &points[k];
        let archive = s.archive.as_deref();
        if archive.is_some_and(|a| split_bottom_study::archived(a, name, spec).is_some()) {
            return;
        }
        let dir = s.out.join(name);
        match pool.install(|| run_cell(name, spec, &dir, archive)) {
            Ok(()) => {
                // Each finished cell goes into the study's database at once.
                let stored = s.database().map(|db| {
                    ResultsDb::open(&db)
                        .and_then(|mut d| d.insert_cell(&s.name, name, &dir.join("summary.json")))
                });
                if let Some(Err(e)) = stored {
                    errors
                        .lock()
                        .map(|mut v| v.push(format!("{name}: {e}")))
                        .ok();
                }
            }
            Err(RunError::Busy(_)) => {
                if !quiet {
                    eprintln!("  {name}: being run by another process; skipped");
                }
            }
            Err(e) => {
                errors
                    .lock()
                    .map(|mut v| v.push(format!("{name}: {e}")))
                    .ok();
            }
        }
    });
    errors.lock().map(|mut v| v.extend(pool_errors)).ok();
    let done = s.finished_cells().len();
    println!("{done} of {} points finished", points.len());
    let errors = errors.into_inner().unwrap_or_default();
    if !errors.is_empty() {
        bail!("{} errors:\n{}", errors.len(), errors.join("\n"));
    }
    Ok(())
}

/// Stores every finished point in the study's database and refreshes its archive's table.
fn collect(s: &Loaded) -> Result<()> {
    if let Points::SplitBottom(_) = s.points {
        let cells = s.finished_cells();
        match s.database() {
            Some(db) => {
                let mut database = ResultsDb::open(&db)?;
                for (name, summary) in &cells {
                    database.insert_cell(&s.name, name, summary)?;
                }
                println!(
                    "{} of {} cells finished; {} stored under study {:?} in {}",
                    cells.len(),
                    s.names().len(),
                    database.count_cells(Some(&s.name))?,
                    s.name,
                    db.display()
                );
            }
            None => println!(
                "{} of {} cells finished; the study names no database to store them in",
                cells.len(),
                s.names().len()
            ),
        }
        return Ok(());
    }
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
                s.names().len(),
                database.count(Some(&s.name))?,
                s.name,
                db.display()
            );
        }
        None => println!(
            "{} of {} points finished; the study names no database to store them in",
            finished.len(),
            s.names().len()
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
    let count = |f: fn(&PointStatus<()>) -> bool| status.iter().filter(|st| f(st)).count();
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
        let stored = match s.points {
            Points::ShearBox(_) => database.count(Some(&s.name))?,
            Points::SplitBottom(_) => database.count_cells(Some(&s.name))?,
        };
        println!("  database {}: {stored} points of {}", db.display(), s.name);
    }
    Ok(())
}
