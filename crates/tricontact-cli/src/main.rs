//! The `tricontact` command-line solver (work in progress).

fn main() {
    eprintln!("tricontact: the solver front end is not built yet");
    std::process::exit(2);
}
