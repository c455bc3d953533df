//! What is generated from the command line's one definition
//! ([`super::args::definition`]): the shell completion scripts
//! (clap_complete) and the man pages (clap_mangen). The help, the pages and
//! the completions cannot disagree: they are the same clap `Command`.
//!
//! Bash gets one addition to clap_complete's script. Its script offers only
//! flags and subcommand names where a positional argument goes, and files
//! after any flag without a list of values (`--threads`): the wrapper here
//! offers files where the argument is a file (the scene, the parts, the
//! images) and nothing after a flag whose value is a number, a region or a
//! PATH=VALUE.

use super::args::definition;
use clap::ValueHint;
use clap_complete::Shell;

/// The completion script for `shell`.
pub fn completions(shell: Shell) -> String {
    let mut command = definition();
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut command, "rayoflight", &mut script);
    let mut script = String::from_utf8_lossy(&script).into_owned();
    if shell == Shell::Bash {
        script.push_str(&bash_paths());
    }
    script
}

/// Whether `arg` takes a file (or folder) name.
fn takes_path(arg: &clap::Arg) -> bool {
    matches!(
        arg.get_value_hint(),
        ValueHint::AnyPath | ValueHint::FilePath | ValueHint::DirPath
    )
}

/// Whether `arg` is a flag with a value that is neither a path nor one of
/// a list (a number, a region, PATH=VALUE): nothing to complete.
fn takes_free_value(arg: &clap::Arg) -> bool {
    let takes_value = arg.get_action().takes_values();
    takes_value
        && !arg.is_positional()
        && !takes_path(arg)
        && arg.get_value_parser().possible_values().is_none()
}

/// The bash wrapper around clap_complete's `_rayoflight`.
fn bash_paths() -> String {
    let mut root = definition();
    root.build();
    let valued = |command: &clap::Command, free: bool| -> Vec<String> {
        command
            .get_arguments()
            .filter(|a| !a.is_positional() && a.get_action().takes_values())
            .filter(|a| takes_free_value(a) == free)
            .flat_map(|a| {
                let long = a.get_long().map(|l| format!("--{l}"));
                let short = a.get_short().map(|s| format!("-{s}"));
                long.into_iter().chain(short)
            })
            .collect()
    };
    let (mut free, mut listed) = (valued(&root, true), valued(&root, false));
    let mut with_files = Vec::new();
    for sub in root.get_subcommands() {
        free.extend(valued(sub, true));
        listed.extend(valued(sub, false));
        if sub.get_positionals().any(takes_path) {
            with_files.push(sub.get_name().to_owned());
        }
    }
    for list in [&mut free, &mut listed] {
        list.sort();
        list.dedup();
    }
    // A flag that is free in one subcommand and a path in another
    // (`-o`): clap's answer, which knows the subcommand, stands.
    free.retain(|f| !listed.contains(f));
    let subcommands: Vec<&str> = root.get_subcommands().map(|s| s.get_name()).collect();
    format!(
        r#"
# Added by rayoflight to clap_complete's script: files where a file goes,
# nothing after a flag whose value is a number, a region or PATH=VALUE.
_rayoflight_files() {{
    _rayoflight "$@"
    local cur="$2" prev="$3"
    case "${{prev}}" in
        {free})
            COMPREPLY=()
            compopt +o default +o bashdefault 2>/dev/null
            return 0
            ;;
        {listed})
            return 0
            ;;
    esac
    [[ ${{cur}} == -* ]] && return 0
    if [[ ${{COMP_CWORD}} -gt 1 ]]; then
        case "${{COMP_WORDS[1]}}" in
            {with_files}) COMPREPLY=() ;;
            {subcommands}) return 0 ;;
            # The top level: the scene, after flags.
            *) COMPREPLY=() ;;
        esac
    fi
    # The first word is a subcommand or the scene.
    compopt -o filenames 2>/dev/null
    COMPREPLY+=( $(compgen -f -- "${{cur}}") )
}}
complete -F _rayoflight_files -o nosort -o bashdefault -o default rayoflight
"#,
        free = free.join("|"),
        listed = listed.join("|"),
        with_files = with_files.join("|"),
        subcommands = subcommands.join("|"),
    )
}

/// Every man page, with its file name: `rayoflight.1`, then
/// `rayoflight-SUBCOMMAND.1` for each subcommand.
pub fn man_pages() -> Result<Vec<(String, String)>, String> {
    let names: Vec<String> = definition()
        .get_subcommands()
        .map(|s| s.get_name().to_owned())
        .collect();
    let mut pages = vec![("rayoflight.1".to_owned(), man_page(None)?)];
    for name in names {
        pages.push((format!("rayoflight-{name}.1"), man_page(Some(&name))?));
    }
    Ok(pages)
}

/// The man page of `subcommand` (`None`: rayoflight(1)), in roff.
pub fn man_page(subcommand: Option<&str>) -> Result<String, String> {
    let mut root = definition();
    root.build();
    let page = match subcommand {
        Some(name) => root
            .find_subcommand(name)
            .cloned()
            .ok_or_else(|| format!("man: no subcommand {name:?}"))?,
        None => root,
    };
    let mut roff = Vec::new();
    clap_mangen::Man::new(page)
        .render(&mut roff)
        .map_err(|e| format!("man: {e}"))?;
    Ok(String::from_utf8_lossy(&roff).into_owned())
}
