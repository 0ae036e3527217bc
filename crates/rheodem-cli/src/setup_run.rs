//! One subcommand per registered set-up (`rheodem shear-box`, `rheodem split-bottom`, …),
//! built from the registry: the set-up's parameters (every option overrides the same key
//! of `--config`) and the options every run takes. A set-up needs no file here.

use crate::progress::Progress;
use crate::setup_args;
use anyhow::{Context, Result};
use clap::{Arg, ArgAction, ArgMatches, Command};
use rheodem::setups::registry::{SETUPS, SetUpInfo};
use rheodem::setups::runner::{Event, RunOptions};
use std::path::{Path, PathBuf};

/// `cli` with one subcommand per registered set-up, listed after its first `after`
/// subcommands (`run` and `resume`).
pub fn with_set_ups(cli: Command, after: usize) -> Command {
    let names: Vec<String> = cli
        .get_subcommands()
        .map(|c| c.get_name().to_string())
        .collect();
    let cli = names.iter().enumerate().fold(cli, |cli, (k, name)| {
        let order = if k < after { k } else { k + SETUPS.len() };
        cli.mut_subcommand(name, |c| c.display_order(order))
    });
    SETUPS.iter().enumerate().fold(cli, |cli, (k, info)| {
        cli.subcommand(subcommand(info).display_order(after + k))
    })
}

/// The subcommand of the set-up `info`.
fn subcommand(info: &SetUpInfo) -> Command {
    let mut cmd = Command::new(info.name)
        .about(info.summary.trim_end_matches('.'))
        .allow_negative_numbers(true)
        .arg(
            Arg::new("config")
                .long("config")
                .value_name("CONFIG")
                .value_parser(clap::value_parser!(PathBuf))
                .help(format!(
                    "A TOML file with the set-up's keys (those of `rheodem setups {}`); the \
                     options override it.",
                    info.name
                )),
        )
        .args(setup_args::arguments(info));
    if let Some(from) = info.from {
        cmd = cmd.arg(
            Arg::new("from")
                .long("from")
                .value_name("FROM")
                .value_parser(clap::value_parser!(PathBuf))
                .help(from),
        );
    }
    cmd = cmd
        .arg(
            Arg::new("out")
                .long("out")
                .short('o')
                .value_name("OUT")
                .value_parser(clap::value_parser!(PathBuf))
                .help(format!("Run directory (default: runs/{}).", info.name)),
        )
        .arg(
            Arg::new("threads")
                .long("threads")
                .short('t')
                .value_name("THREADS")
                .value_parser(clap::value_parser!(usize))
                .help("Worker threads (default: all logical CPUs)."),
        )
        .arg(
            Arg::new("force")
                .long("force")
                .action(ArgAction::SetTrue)
                .help(
                    "Start over even if the directory holds a run of other settings \
                     (otherwise the same settings resume and others are refused).",
                ),
        )
        .arg(
            Arg::new("quiet")
                .long("quiet")
                .short('q')
                .action(ArgAction::SetTrue)
                .help("No progress bar."),
        );
    if info.estimates_memory {
        cmd = cmd.arg(
            Arg::new("max_memory")
                .long("max-memory")
                .value_name("SIZE")
                .help(
                    "Refuse a run whose estimated memory exceeds this size (e.g. 8GiB, \
                     500MB; default: the machine's physical memory).",
                ),
        );
    }
    cmd
}

/// The base table of `--config` (empty without one).
fn config_table(config: Option<&Path>) -> Result<toml::Table> {
    let Some(path) = config else {
        return Ok(toml::Table::new());
    };
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    toml::from_str(&text).with_context(|| format!("{} is not valid TOML", path.display()))
}

/// Runs the set-up `info` with the options of `m`: prints its notes and warnings on
/// standard error, its progress, and its report on standard output.
pub fn run(info: &SetUpInfo, m: &ArgMatches) -> Result<()> {
    let config = m.get_one::<PathBuf>("config");
    let base = config_table(config.map(PathBuf::as_path))?;
    let values = setup_args::values(info, m);
    // The values are checked before anything else is done, naming the key.
    (info.accepts)(base.clone(), &values).with_context(|| match config {
        Some(path) => format!("{} from {} and the options", info.name, path.display()),
        None => format!("{} options", info.name),
    })?;
    let max_memory = if info.estimates_memory {
        crate::memory_limit(m.get_one::<String>("max_memory").map(String::as_str))?
    } else {
        None
    };
    let (pool, threads) = crate::pool(m.get_one::<usize>("threads").copied())?;
    let dir = m
        .get_one::<PathBuf>("out")
        .cloned()
        .unwrap_or_else(|| Path::new("runs").join(info.name));
    let options = RunOptions {
        dir: &dir,
        threads,
        force: m.get_flag("force"),
        // Only set-ups that can start from a run have the option.
        from: m
            .try_get_one::<PathBuf>("from")
            .ok()
            .flatten()
            .map(PathBuf::as_path),
        max_memory,
    };
    let quiet = m.get_flag("quiet");
    let mut progress: Option<Progress> = None;
    let mut events = |event: Event<'_>| match event {
        Event::Particles(n) => progress = Some(Progress::new(quiet, n)),
        Event::Note(text) if !quiet => match &progress {
            Some(p) => p.note(text),
            None => eprintln!("{text}"),
        },
        Event::Note(_) => {}
        Event::Warning(text) => match &progress {
            Some(p) => p.note(&format!("warning: {text}")),
            None => eprintln!("warning: {text}"),
        },
        Event::Progress(p) => {
            if let Some(bar) = &progress
                && (p.done.is_multiple_of(64) || p.done == p.total)
            {
                bar.update(p.stage, p.done, p.total);
            }
        }
    };
    let finished = pool.install(|| (info.run)(base, &values, &options, &mut events));
    if let Some(p) = &progress {
        p.finish();
    }
    let finished = finished.map_err(|e| match e {
        rheodem::run::RunError::Mismatch(_) => {
            anyhow::anyhow!("{e}; or pass --force to start it over with the new settings")
        }
        other => other.into(),
    })?;
    print!("{}", finished.report);
    for w in &finished.warnings {
        eprintln!("warning: {w}");
    }
    Ok(())
}
