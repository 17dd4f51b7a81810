//! The `nlrom` binary: `mesh info` output and exit statuses (`interface.md`).

use std::path::Path;
use std::process::Command;

fn nlrom(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_nlrom"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("runs")
}

#[test]
fn mesh_info_json_has_the_contract_keys() {
    let out = nlrom(&[
        "mesh",
        "info",
        "meshes/formats/sector_conforming.v41-binary.msh",
        "--json",
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_slice(&out.stdout).expect("one JSON object on stdout");
    assert_eq!(v["format"], "4.1");
    assert_eq!(v["binary"], true);
    assert_eq!(v["nodes"], 3914);
    assert_eq!(v["elements"]["tetra10"], 1878);
    let hub = v["groups"]
        .as_array()
        .expect("groups")
        .iter()
        .find(|g| g["name"] == "hub")
        .expect("hub");
    assert_eq!(
        (
            hub["dim"].as_u64(),
            hub["elements"].as_u64(),
            hub["nodes"].as_u64()
        ),
        (Some(2), Some(14), Some(37))
    );
    assert_eq!(v["bbox"][1][0], 0.26);
    assert!(v["wall_seconds"].as_f64().is_some());
}

#[test]
fn mesh_info_text_lists_groups() {
    let out = nlrom(&["mesh", "info", "meshes/formats/bar_hex20.v22-ascii.msh"]);
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("MSH 2.2 ASCII") && text.contains("hexa20") && text.contains("clamp"),
        "{text}"
    );
}

#[test]
fn bad_input_exits_2_with_the_file_and_line() {
    let out = nlrom(&["mesh", "info", "tests/data/broken/trailing_token.msh"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("trailing_token.msh: line 10") && err.contains("$Elements"),
        "{err}"
    );
    assert!(out.stdout.is_empty());
    let out = nlrom(&["mesh", "info", "no/such.msh"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no/such.msh"));
}

#[test]
fn unimplemented_commands_exit_1_and_every_command_has_help() {
    for cmd in [
        "modes", "export", "reduce", "contact", "solve", "march", "run", "batch", "demo", "mesh",
    ] {
        let out = nlrom(&[cmd, "--help"]);
        assert_eq!(out.status.code(), Some(0), "{cmd} --help");
        assert!(!out.stdout.is_empty());
    }
    assert!(Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("meshes/sector_conforming.msh")
        .exists());
    let out = nlrom(&["solve", "case.toml", "-o", "r.h5"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not implemented yet"));
}
