//! nauta's offline tools as libraries, each testable without the command
//! line (DESIGN §3, §9): [`eval`] (accuracy of every estimate stream of a
//! recording), [`report`] (its plots and table), [`export`] (KML, GeoJSON,
//! GPX, CSV, Foxglove), [`import`] (outside data sets into recordings),
//! [`calibrate`] (magnetometer calibration from a recording or the
//! simulator), [`lbl_plan`] (paper 003's sensitivity maps and operating box
//! of a transponder layout), [`smooth`] (paper 004's post-mission smoother
//! of a recording's LBL navigation). They read recordings through `nauta_log`'s one reader
//! ([`nauta_log::streams`], [`nauta_log::run`]); [`presets`] is what the
//! simulator adds to a recording's run metadata.

pub mod calibrate;
pub mod eval;
pub mod export;
pub mod import;
pub mod lbl_plan;
pub mod part_file;
pub mod presets;
pub mod progress;
pub mod report;
pub mod smooth;
