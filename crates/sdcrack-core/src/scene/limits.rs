//! What a scene may ask for: the largest level, the memory estimate of a level's solve and the
//! check of both, known before anything is meshed or allocated.

/// Largest refinement level accepted (4^13 · cells would not fit in memory anyway).
pub const MAX_LEVEL: u32 = 12;

/// Largest estimated peak memory of one level's solve accepted before anything is allocated
/// ([`estimated_memory_bytes`]): 16 GiB.
pub const MAX_MEMORY_BYTES: u64 = 16 << 30;

/// The size of a scene's level-0 mesh, known before it is made (memory estimates).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Level0Size {
    /// The structured grid's cells per direction.
    Grid([usize; 2]),
    /// Triangles of an unstructured level 0: counted for a mesh file, estimated for gmsh as
    /// |Ω| over the area √3/4 h² of an equilateral triangle of edge h, times 1.5.
    Triangles(f64),
}

impl Level0Size {
    /// Cells of a structured grid of the same work at `level` (a cell is two triangles).
    fn cells_at(self, level: u32) -> f64 {
        let n0 = match self {
            Level0Size::Grid(c) => (c[0] as f64) * (c[1] as f64),
            Level0Size::Triangles(t) => t / 2.0,
        };
        n0 * 4f64.powi(level.min(64) as i32)
    }

    /// What level `level` is, in words ("a 256×256 grid", "about 131072 triangles").
    fn describe(self, level: u32) -> String {
        match self {
            Level0Size::Grid(c) => {
                let scale = 1u64 << level.min(62);
                format!(
                    "level {level} of cells [{}, {}] is a {}×{} grid",
                    c[0],
                    c[1],
                    (c[0] as u64).saturating_mul(scale),
                    (c[1] as u64).saturating_mul(scale)
                )
            }
            Level0Size::Triangles(_) => format!(
                "level {level} has about {:.2e} triangles",
                2.0 * self.cells_at(level)
            ),
        }
    }
}

/// Estimated peak memory, in bytes, of solving level `level` of a grid of `cells` level-0 cells:
/// [`MEMORY_BASE_BYTES`] plus [`estimated_mesh_memory_bytes`] (the fill of the sparse LDLᵀ of a
/// 2D grid under nested dissection grows like n log n). Measured peaks are in docs/design.md; the
/// estimate is above each of them.
pub fn estimated_memory_bytes(size: Level0Size, level: u32) -> u64 {
    estimated_memory_bytes_of_cells(size.cells_at(level))
}

/// [`estimated_memory_bytes`] of a mesh of `n` cells (half its triangle count), known once the
/// mesh is made (a graded mesh: more cells than its level-0 grid times 4^level).
pub fn estimated_memory_bytes_of_cells(n: f64) -> u64 {
    let bytes = MEMORY_BASE_BYTES as f64 + estimated_mesh_memory_bytes(n);
    if bytes >= u64::MAX as f64 {
        u64::MAX
    } else {
        bytes as u64
    }
}

/// The part of [`estimated_memory_bytes`] that does not grow with the mesh: 128 MiB (the
/// process, its libraries, fixed buffers).
pub const MEMORY_BASE_BYTES: u64 = 128 << 20;

/// The part of [`estimated_memory_bytes`] that grows with the mesh, for `n` cells:
/// [`MEMORY_BYTES_PER_CELL`] · n · log₂ n. The campaign workflow sizes the Python jobs of a level
/// (references, checks, the report) by it too (`sdcrack check --json`'s `mesh_memory_mb`).
pub fn estimated_mesh_memory_bytes(n: f64) -> f64 {
    MEMORY_BYTES_PER_CELL * n * n.max(2.0).log2()
}

/// Bytes per cell per log2(cells) in [`estimated_memory_bytes`].
pub const MEMORY_BYTES_PER_CELL: f64 = 600.0;

/// Checks one refinement level of a grid of `cells` level-0 cells: at most [`MAX_LEVEL`] and an
/// [`estimated_memory_bytes`] within [`MAX_MEMORY_BYTES`]. The message names the level, not the
/// key (the scene's `discretization.levels` or the command line's `--level`).
pub fn check_level(size: Level0Size, level: u32) -> Result<(), String> {
    if level > MAX_LEVEL {
        return Err(format!("level {level} is outside 0..={MAX_LEVEL}"));
    }
    let memory = estimated_memory_bytes(size, level);
    if memory > MAX_MEMORY_BYTES {
        let fewer = match size {
            Level0Size::Grid(_) => "fewer cells",
            Level0Size::Triangles(_) => "a larger mesh_size",
        };
        return Err(format!(
            "{}, which needs an estimated {:.1} GiB, more than the {} GiB limit; use a lower level or {fewer}",
            size.describe(level),
            memory as f64 / (1u64 << 30) as f64,
            MAX_MEMORY_BYTES >> 30
        ));
    }
    Ok(())
}
