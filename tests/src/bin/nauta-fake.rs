//! `nauta-fake`: a service binary that only describes itself, for the
//! launcher's wiring tests. `--describe` prints the JSON in the environment
//! variable `NAUTA_FAKE_DESCRIBE`; `--check` accepts anything; started for
//! real, it refuses to run (the tests never get that far).

use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "--describe") {
        match std::env::var("NAUTA_FAKE_DESCRIBE") {
            Ok(json) => {
                println!("{json}");
                ExitCode::SUCCESS
            }
            Err(_) => {
                eprintln!("nauta-fake: set NAUTA_FAKE_DESCRIBE to the JSON to describe");
                ExitCode::FAILURE
            }
        }
    } else if args.iter().any(|a| a == "--check") {
        ExitCode::SUCCESS
    } else {
        eprintln!("nauta-fake: describes itself only");
        ExitCode::FAILURE
    }
}
