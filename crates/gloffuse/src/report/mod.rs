//! ⑤ Report: renderers of the verdicts, verify's in `verify` and the audit's in `audit`,
//! each with its report folder; and what both share: `png` (PNG helpers: the grey
//! background, the font, atomic writes), `false_colour` (the diverging scale), `page` (a
//! report page's style and banner, HTML escaping), `escape` (users' names made safe for a
//! terminal and for XML).

pub mod audit;
pub mod escape;
pub mod false_colour;
pub mod page;
pub mod png;
pub mod verify;

use std::path::Path;

use crate::Error;
use crate::output;

/// Checks that `dir` can become a report folder: it is made if missing, but its parent
/// must exist. Called before any slow work.
pub fn check_dir(dir: &Path) -> Result<(), Error> {
    output::report_dir(dir)
}
