//! The commands on a full disk: exit 1 with the file and the OS reason named, no 0-byte or cut
//! file and no temporary left, never `SIGBUS`. Uses a small tmpfs when the tests run as root
//! (CI containers); elsewhere each test says it skipped and the fault-injection tests beside
//! each writer cover the same paths.

use std::path::Path;

use aerie_io::tmpfs::SmallTmpfs;

fn aerie(args: &[&str]) -> Result<(), aerie::app::failure::Failure> {
    use clap::Parser as _;
    let mut v = vec!["aerie"];
    v.extend_from_slice(args);
    let cli = aerie::app::cli::Cli::try_parse_from(v).expect("arguments parse");
    aerie::app::cli::run(cli)
}

fn disk(bytes: u64) -> Option<SmallTmpfs> {
    match SmallTmpfs::mount(bytes) {
        Ok(d) => Some(d),
        Err(why) => {
            eprintln!("skipped (no small tmpfs: {why})");
            None
        }
    }
}

fn gen_dem(out: &Path, size: usize) -> Result<(), aerie::app::failure::Failure> {
    aerie(&[
        "gen-dem",
        "--size",
        &size.to_string(),
        "--kind",
        "ridged",
        "--out",
        out.to_str().unwrap(),
    ])
}

#[test]
fn gen_dem_onto_a_full_disk_fails_naming_the_file_and_leaves_nothing() {
    let Some(d) = disk(64 * 1024) else { return };
    // 257² f32 = 264 KiB: its blocks cannot be reserved on a 64 KiB disk.
    let out = d.path().join("dem.f32");
    let f = gen_dem(&out, 257).unwrap_err();
    assert_eq!(f.code, 1, "{}", f.message);
    assert!(f.message.contains("dem.f32"), "{}", f.message);
    assert!(
        f.message.contains("No space left on device"),
        "{}",
        f.message
    );
    assert!(d.entries().is_empty(), "{:?}", d.entries());
}

#[test]
fn bake_onto_a_full_disk_fails_naming_the_bake_and_leaves_nothing() {
    let Some(d) = disk(8 * 1024) else { return };
    let src = tempfile::tempdir().unwrap();
    let dem = src.path().join("dem.f32");
    gen_dem(&dem, 257).unwrap_or_else(|f| panic!("{}", f.message));
    let out = d.path().join("dem.f32.aerie-bake");
    let f = aerie(&[
        "bake",
        dem.to_str().unwrap(),
        "--tile-size",
        "3",
        "--out",
        out.to_str().unwrap(),
    ])
    .unwrap_err();
    assert_eq!(f.code, 1, "{}", f.message);
    assert!(f.message.contains("dem.f32.aerie-bake"), "{}", f.message);
    assert!(
        f.message.contains("No space left on device"),
        "{}",
        f.message
    );
    assert!(d.entries().is_empty(), "{:?}", d.entries());
}

#[test]
fn the_bake_next_to_a_dataset_on_a_full_disk_is_an_error_not_sigbus() {
    // The dataset fits, its bake (written by `bake`, and by render/fly/run through the same
    // writer) does not.
    let Some(d) = disk(96 * 1024) else { return };
    let dem = d.path().join("dem.f32");
    gen_dem(&dem, 129).unwrap_or_else(|f| panic!("{}", f.message));
    let before = d.entries();
    assert_eq!(before, ["dem.f32", "dem.f32.json"]);
    let f = aerie(&["bake", dem.to_str().unwrap(), "--tile-size", "3"]).unwrap_err();
    assert_eq!(f.code, 1, "{}", f.message);
    assert!(f.message.contains("dem.f32.aerie-bake"), "{}", f.message);
    assert!(
        f.message.contains("No space left on device"),
        "{}",
        f.message
    );
    assert_eq!(d.entries(), before, "a temporary or cut bake was left");
}

#[test]
fn render_fly_run_prepare_bakes_in_memory_when_the_disk_next_to_the_dataset_is_full() {
    let Some(d) = disk(96 * 1024) else { return };
    let dem = d.path().join("dem.f32");
    gen_dem(&dem, 129).unwrap_or_else(|f| panic!("{}", f.message));
    let before = d.entries();
    // The bake cannot be saved: the command goes on with the bake in memory, no crash, and
    // neither a cut bake nor a temporary is left next to the dataset.
    let (ds, b) =
        aerie::app::prepare::prepare_terrain(&dem, 3).unwrap_or_else(|f| panic!("{}", f.message));
    assert_eq!(b.width as usize, ds.hf.width);
    assert_eq!(d.entries(), before);
}

/// Fills the disk to its last byte with one file, so that no write at all fits.
fn fill(d: &SmallTmpfs) {
    use std::io::Write;
    let mut f = std::fs::File::create(d.path().join("filler")).unwrap();
    let block = vec![0u8; 4096];
    loop {
        match f.write(&block) {
            Ok(0) => break,
            Ok(_) => {}
            Err(e) => {
                assert_eq!(e.raw_os_error(), Some(28), "{e}");
                break;
            }
        }
    }
}

/// A small synthetic DEM (with its bake) on a normal disk.
fn dem_elsewhere() -> (tempfile::TempDir, std::path::PathBuf) {
    let src = tempfile::tempdir().unwrap();
    let dem = src.path().join("dem.f32");
    gen_dem(&dem, 129).unwrap_or_else(|f| panic!("{}", f.message));
    aerie(&["bake", dem.to_str().unwrap()]).unwrap_or_else(|f| panic!("{}", f.message));
    (src, dem)
}

#[test]
fn render_onto_a_full_disk_exits_1_naming_the_png_and_leaves_no_empty_png() {
    let Some(d) = disk(16 * 1024) else { return };
    let (_src, dem) = dem_elsewhere();
    fill(&d);
    let out = d.path().join("out.png");
    let f = aerie(&[
        "render",
        "--dem",
        dem.to_str().unwrap(),
        "--camera",
        "640,-300,900,0,-30,0",
        "--size",
        "64x48",
        "--out",
        out.to_str().unwrap(),
    ])
    .unwrap_err();
    assert_eq!(f.code, 1, "{}", f.message);
    assert!(f.message.contains("out.png"), "{}", f.message);
    assert!(
        f.message.contains("No space left on device"),
        "{}",
        f.message
    );
    assert_eq!(d.entries(), ["filler"]);
}

#[test]
fn run_stats_onto_a_full_disk_exits_1_naming_the_csv_and_leaves_no_cut_csv() {
    let Some(d) = disk(16 * 1024) else { return };
    let (_src, dem) = dem_elsewhere();
    fill(&d);
    let stats = d.path().join("stats.csv");
    let f = aerie(&[
        "run",
        "--headless",
        "--dem",
        dem.to_str().unwrap(),
        "--frames",
        "3",
        "--size",
        "64x48",
        "--stats",
        stats.to_str().unwrap(),
    ])
    .unwrap_err();
    assert_eq!(f.code, 1, "{}", f.message);
    assert!(f.message.contains("stats.csv"), "{}", f.message);
    assert!(
        f.message.contains("No space left on device"),
        "{}",
        f.message
    );
    assert_eq!(d.entries(), ["filler"]);
}
