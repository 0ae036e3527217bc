//! `rheodem setups`: the registered set-ups and their parameters.

use anyhow::{Result, anyhow};
use clap::Args;
use rheodem::setups::registry::{self, SETUPS};

/// Arguments of `setups`.
#[derive(Args)]
pub struct SetupsArgs {
    /// A set-up's name: print its parameters (key, unit, meaning, allowed values, default)
    /// as a markdown table. Without a name: every set-up with its summary.
    name: Option<String>,
    /// Print every set-up's parameter table (markdown, as in docs/setups.md).
    #[arg(long, conflicts_with = "name")]
    markdown: bool,
}

/// Runs `setups`.
pub fn run(args: &SetupsArgs) -> Result<()> {
    match (&args.name, args.markdown) {
        (Some(name), _) => {
            let info = registry::find(name).map_err(|e| anyhow!(e))?;
            print!("{}", info.markdown());
        }
        (None, true) => {
            let sections: Vec<String> = SETUPS.iter().map(|s| s.markdown()).collect();
            print!("{}", sections.join("\n"));
        }
        (None, false) => {
            for s in SETUPS {
                println!("{:<14} {}", s.name, s.summary);
            }
        }
    }
    Ok(())
}
