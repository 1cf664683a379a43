//! A rendered run folder for tests: the paper's 18 configurations, `key.csv` with seeded
//! anonymous names, and a tiny valid GIF per name in `render/` (the server only serves them).

#![allow(dead_code)]

use std::path::Path;

/// The paper's configurations (`name,object,lattice,clustering`).
pub const CONFIGURATIONS: &str = include_str!("../../../render/tests/fixtures/configurations.csv");

/// A 1x1 GIF.
pub const TINY_GIF: &[u8] = &[
    0x47, 0x49, 0x46, 0x38, 0x39, 0x61, 0x01, 0x00, 0x01, 0x00, 0x80, 0x00, 0x00, 0xff, 0xff, 0xff,
    0x00, 0x00, 0x00, 0x21, 0xf9, 0x04, 0x01, 0x00, 0x00, 0x00, 0x00, 0x2c, 0x00, 0x00, 0x00, 0x00,
    0x01, 0x00, 0x01, 0x00, 0x00, 0x02, 0x02, 0x44, 0x01, 0x00, 0x3b,
];

/// Configuration ids of the fixture, in file order.
pub fn ids() -> Vec<String> {
    CONFIGURATIONS
        .lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.split(',').next().unwrap_or("").trim().to_string())
        .collect()
}

/// Writes the run folder into `run` and returns the names, in configuration order.
pub fn write_run(run: &Path) -> Vec<String> {
    std::fs::create_dir_all(run.join("render")).unwrap();
    std::fs::write(run.join("configurations.csv"), CONFIGURATIONS).unwrap();
    let ids = ids();
    // Four consonants each, distinct, unrelated to the ids.
    let letters = b"bcdfghjklmnpqrstvwxz";
    let names: Vec<String> = (0..ids.len())
        .map(|k| {
            [
                k * 7 % 20,
                (k * 3 + 5) % 20,
                (k + 11) % 20,
                (k * 13 + 2) % 20,
            ]
            .iter()
            .map(|&i| letters[i] as char)
            .collect()
        })
        .collect();
    let mut key = String::from("name,id\n");
    for (id, name) in ids.iter().zip(&names) {
        key.push_str(&format!("{name},{id}\n"));
        std::fs::write(run.join("render").join(format!("{name}.gif")), TINY_GIF).unwrap();
    }
    std::fs::write(run.join("key.csv"), key).unwrap();
    std::fs::write(run.join("render").join("settings.json"), "{}\n").unwrap();
    names
}
