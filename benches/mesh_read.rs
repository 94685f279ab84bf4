//! Reading a gmsh MSH 4.1 file (parsing, splitting into bodies and groups, checking every
//! cell): the fastest of several reads in rayon pools of 1 and 2 threads, a check that both
//! give the same mesh byte for byte, and a fingerprint of it (SipHash of its serialized bytes,
//! `std`'s fixed keys) to compare the meshes two builds read.
//!
//! ```sh
//! cargo bench --bench mesh_read -- FILE.msh [REPEATS]
//! ```
//!
//! The memory model's 1M-DOF mesh (`validation/memory_model.py`, `case_file(2.02)`) is the one
//! a distributed run's rank 0 reads alone before it partitions the mesh (`docs/parallel.md`).

use std::hash::{DefaultHasher, Hasher};
use std::path::PathBuf;
use std::time::Instant;

use internodes::mesh::read_msh;

const REPEATS: usize = 5;
const THREADS: [usize; 2] = [1, 2];

fn main() {
    // `cargo bench` passes `--bench` to harness-less benches; the file is the first other
    // argument.
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let Some(file) = args.first().map(PathBuf::from) else {
        eprintln!("usage: cargo bench --bench mesh_read -- FILE.msh [REPEATS]");
        std::process::exit(2);
    };
    let repeats = match args.get(1).map(|r| r.parse::<usize>()) {
        None => REPEATS,
        Some(Ok(r)) if r > 0 => r,
        Some(_) => {
            eprintln!("REPEATS: a positive integer");
            std::process::exit(2);
        }
    };
    let megabytes = std::fs::metadata(&file)
        .map(|m| m.len() as f64 / 1e6)
        .unwrap_or_else(|e| {
            eprintln!("{}: {e}", file.display());
            std::process::exit(1);
        });
    let pools: Vec<rayon::ThreadPool> = THREADS
        .iter()
        .map(|&n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .expect("a rayon pool")
        })
        .collect();
    let mut fastest = [f64::INFINITY; THREADS.len()];
    let mut bytes: [Option<Vec<u8>>; THREADS.len()] = [None, None];
    let mut sizes = String::new();
    // Alternately, so that the machine's other load spreads over both thread counts.
    for _ in 0..repeats {
        for (k, pool) in pools.iter().enumerate() {
            let start = Instant::now();
            let mesh = pool.install(|| read_msh(&file)).unwrap_or_else(|e| {
                eprintln!("{e}");
                std::process::exit(1);
            });
            fastest[k] = fastest[k].min(start.elapsed().as_secs_f64());
            let serialized = postcard::to_allocvec(&mesh).expect("a mesh serializes");
            if bytes[k].as_ref().is_some_and(|b| *b != serialized) {
                eprintln!("two reads with {} threads differ", THREADS[k]);
                std::process::exit(1);
            }
            bytes[k] = Some(serialized);
            sizes = (mesh.bodies.iter())
                .map(|b| {
                    format!(
                        "'{}' {} nodes, {} cells",
                        b.name,
                        b.num_nodes(),
                        b.num_cells()
                    )
                })
                .collect::<Vec<_>>()
                .join("; ");
        }
    }
    println!("{} ({megabytes:.1} MB): {sizes}", file.display());
    println!("fastest of {repeats} reads, seconds (MB/s)");
    for (threads, seconds) in THREADS.iter().zip(fastest) {
        println!(
            "  {threads} thread(s): {seconds:.3} ({:.0})",
            megabytes / seconds
        );
    }
    let same = bytes[0] == bytes[1];
    let mut fingerprint = DefaultHasher::new();
    fingerprint.write(bytes[0].as_deref().unwrap_or_default());
    println!("mesh fingerprint: {:016x}", fingerprint.finish());
    println!(
        "the meshes read with 1 and 2 threads: {}",
        if same { "identical" } else { "DIFFERENT" }
    );
    if !same {
        std::process::exit(1);
    }
}
