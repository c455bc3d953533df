//! At home on the desktop, in the shell and in the editor: completions, man
//! pages, the schema, the desktop entry and scene type, and `rayoflight lsp`
//! with a real client.

#[path = "../common/mod.rs"]
mod common;

mod home;
mod lsp;
