//! docs/setups.md lists every registered set-up's parameters as `rheodem setups --markdown`
//! prints them from the set-ups' own declarations, so that the page cannot drift from the
//! code: each set-up's section must appear in it verbatim.

use rheodem::setups::registry::SETUPS;
use std::path::Path;

#[test]
fn the_parameter_reference_is_the_registry() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/setups.md");
    let page = std::fs::read_to_string(&file).expect("docs/setups.md");
    for s in SETUPS {
        let section = s.markdown();
        assert!(
            page.contains(&section),
            "docs/setups.md does not hold the current parameters of `{}`; regenerate its \
             tables with `rheodem setups --markdown`. Expected:\n{section}",
            s.name
        );
    }
}
