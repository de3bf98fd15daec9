//! `psdcal map`: AoA and position error maps over the sensor area (the
//! paper's Figure 9; the library's `map_table`).

use std::path::Path;

use psdcal::MapRequest;

use crate::messages::Output;

/// Runs `map`.
pub fn run(request: &MapRequest, out: Option<&Path>, output: Output) -> anyhow::Result<()> {
    let map = psdcal::map_table(request)?;
    map.table.write_to(out)?;
    crate::messages::emit(output, &map.summary(request, out))
}
