#pragma once
// The correspondence rows of the stability map (docs/atlas.md): zero-energy modes on the
// plane of horizon ratio m and stabilisation coefficient G.
#include <string>

#include "atlas.hpp"

namespace breccia::atlas {

// Adds one row per (m, G) to the stability table and writes the per-run time series of the
// non-affine energy ratio to `series_csv` (beside the stability table: as shipped,
// docs/atlas/stability_correspondence_series.csv).
void stability_correspondence(const SweepPlan& plan, SpecimenMaker& maker, CsvTable& table,
                              const std::string& series_csv);

}  // namespace breccia::atlas
