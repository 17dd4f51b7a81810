use std::path::Path;
#[test]
fn show() {
    let full = std::fs::read_to_string("tests/case_file.rs").unwrap();
    let start = full.find("r#\"title").unwrap() + 3;
    let end = full[start..].find("\"#;").unwrap() + start;
    let f = &full[start..end];
    let variants = [
        f.replace("mu = 0.5", "muu = 0.5"),
        f.replace("young = 210e9", "youngs = 210e9"),
        f.replace("[harmonic_balance]", "[harmonic_balanse]"),
        f.replace("sectors = 24", "sectors = \"24\""),
        f.replace("periods = 20", "periods = = 20"),
        f.replace("step_hz = 2.0", "step_hz = 2.0\nend_rad_s = 9000.0"),
        f.replace("{ modal = 0.002 }", "{ modal = 0.002, rayleigh = [1.0, 1e-6] }"),
        f.replace("force = [0.0, 0.0, 1.0]", "force = [0.0, 1.0]"),
        f.replace("scheme = \"piecewise-linear\"", "scheme = \"rk4\""),
        f.replace("model = \"sama\"", "model = \"samma\""),
        f.replace("name = \"shroud\"\n", ""),
        f.replace("interface_modes = 30", "interface_modes = -3"),
        f.replace("[model]", "[modle]"),
        f.replace("\"contact.shroud.n0\"", "\"contact.shrud.n0\""),
        f.replace("time_samples = 64", "time_samples = 7"),
    ];
    for v in variants {
        match nlrom::case::Case::from_str(&v, Path::new("cases/shroud.toml")) {
            Err(e) => println!("{e}\n"),
            Ok(_) => println!("OK\n"),
        }
    }
}
