//! The limits of a scene file: its size and its level-0 cells.

/// Largest number of level-0 cells per direction.
pub const MAX_CELLS: usize = 4096;
/// Largest scene file accepted, in bytes (1 MiB; the repository's scenes are under 2 KiB).
pub const MAX_SCENE_BYTES: usize = 1 << 20;
