//! The `nlrom` command: a thin wrapper over [`nlrom::cli`].

fn main() {
    std::process::exit(nlrom::cli::main());
}
