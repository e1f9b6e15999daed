//! The `finrs` command line.
fn main() {
    println!("finrs");
}
