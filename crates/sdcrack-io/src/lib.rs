//! sdcrack-io — sdcrack's formats: the TOML scene ([`scene`], validated into sdcrack-core's
//! `Scene`) and the results folder ([`output`]: `summary.json`, HDF5/XDMF fields, the mesh
//! export, `sdcrack merge`). The maths and the study are sdcrack-core's; this crate only reads
//! and writes them.

// The core modules under their own names, as these modules have always called them.
pub mod did_you_mean;
pub mod one_line;
pub mod output;
pub mod plain;
pub mod scene_file;
