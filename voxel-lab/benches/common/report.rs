//! What the benches that write a table to `results/` share: the heading that names the
//! machine and its load, the rows printed as they come, the file written at the end, and
//! a fixed stream of numbers to scatter things with, the sizes a run takes from the
//! environment and the median of timings.

use std::path::Path;

/// A table in Markdown: printed as it grows, written to `results/` by [`Report::write`].
pub struct Report {
    text: String,
}

impl Report {
    /// Headed `# cargo bench -p voxel-lab --bench BENCH (ADAPTER; N cores, load average
    /// L)`, then `detail` (if any) on the heading line.
    pub fn new(bench: &str, adapter: &str, detail: &str) -> Self {
        let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
        let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
        let load = load.split_whitespace().next().unwrap_or("?").to_owned();
        let mut report = Self {
            text: String::new(),
        };
        report.line(&format!(
            "# cargo bench -p voxel-lab --bench {bench} ({adapter}; {cores} cores, load average {load}){detail}\n"
        ));
        report
    }

    /// Adds `line` (and prints it).
    pub fn line(&mut self, line: &str) {
        println!("{line}");
        self.text += line;
        self.text += "\n";
    }

    /// Writes the table to `results/FILE`.
    pub fn write(&self, file: &str) -> voxel_lab::Result<()> {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../results")
            .join(file);
        voxel_render::readback::write_file(&path, self.text.as_bytes())?;
        println!("wrote {}", path.display());
        Ok(())
    }
}

/// Numbers in [0, 1) from `seed` (xorshift64, the top 53 bits): the same on every run.
pub fn numbers(mut seed: u64) -> impl FnMut() -> f64 {
    move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The sizes in `var` (comma-separated), or `default` (not every bench takes any).
#[allow(dead_code)]
pub fn list(var: &str, default: &[usize]) -> Vec<usize> {
    std::env::var(var)
        .ok()
        .map(|v| v.split(',').filter_map(|s| s.trim().parse().ok()).collect())
        .unwrap_or_else(|| default.to_vec())
}

/// The median of `v` (sorted in place; not every bench times rounds).
#[allow(dead_code)]
pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}
