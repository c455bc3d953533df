//! What is generated: the shell completion scripts (clap_complete) and the
//! man pages (clap_mangen), from the command line's one definition
//! ([`super::args::definition`], which their subcommands are given when
//! they run), and the scene format's XML Schema, from the loader's tables.
//! The help, the pages and the completions cannot disagree: they are the
//! same clap `Command`. The subcommands `completions`, `man` and `schema`
//! live here.
//!
//! Bash, zsh and fish get their scripts mended, so that the three offer
//! the same (tests/desktop/home.rs runs one table of cases in each real
//! shell). Bash's script offers only flags and subcommand names where a
//! positional argument goes, and files after any flag without a list of
//! values (`--threads`): the wrapper here offers files where the argument
//! is a file (the scene, the parts, the images) and nothing after a flag
//! whose value is a number, a region or a PATH=VALUE. Zsh's read the first
//! word as the scene and the second as the subcommand
//! ([`zsh_first_word`]); fish's lost every flag's values at the top level
//! and had none for a subcommand's listed positional ([`fish_values`]).

use super::failure::{Failure, fail, usage};
use super::stdout;
use super::subcommand::Subcommand;
use super::usage::UsageError;
use clap::ValueHint;
use clap_complete::Shell;
use rayoflight::system::files;
use std::path::PathBuf;

/// The command line's definition ([`super::args::definition`]).
type Definition = fn() -> clap::Command;

/// Print the XML Schema (XSD 1.0) of the scene format.
///
/// Generated from the loader's own tables: every element and
/// attribute, which are required, the ranges and the numbers the
/// loader reads, each documented (what editors show on hover). Save
/// it as rayoflight.xsd and point the editor at it; see the README.
#[derive(clap::Args, Debug, Clone, PartialEq)]
#[command(override_usage = "rayoflight schema")]
pub(super) struct SchemaFlags {}

impl Subcommand for SchemaFlags {
    type Args = SchemaFlags;

    fn resolve(self, _: &clap::ArgMatches) -> Result<SchemaFlags, UsageError> {
        Ok(self)
    }

    fn prints(_: &SchemaFlags) -> bool {
        true
    }

    fn run(_: SchemaFlags, _: Definition) -> Result<(), Failure> {
        stdout::line(rayoflight::scene::schema::xsd().trim_end())
    }
}

/// Print the shell completion script for SHELL.
///
/// Completes subcommands, flags, file names where a file goes and the
/// names --method, --pass and --add take. For bash:
/// rayoflight completions bash > ~/.local/share/bash-completion/completions/rayoflight
#[derive(clap::Args, Debug, Clone, PartialEq)]
#[command(override_usage = "rayoflight completions SHELL")]
pub(super) struct CompletionsFlags {
    /// The shell.
    #[arg(value_name = "SHELL")]
    pub shell: Shell,
}

impl Subcommand for CompletionsFlags {
    type Args = CompletionsFlags;

    fn resolve(self, _: &clap::ArgMatches) -> Result<CompletionsFlags, UsageError> {
        Ok(self)
    }

    fn prints(_: &CompletionsFlags) -> bool {
        true
    }

    fn run(args: CompletionsFlags, definition: Definition) -> Result<(), Failure> {
        stdout::write(&completions(args.shell, definition)).map_err(Failure::Error)
    }
}

/// Print a man page: rayoflight(1), or one subcommand's.
///
/// For example: rayoflight man | man -l -, rayoflight man edit, or
/// rayoflight man --dir ~/.local/share/man/man1 for every page.
#[derive(clap::Args, Debug, Clone, PartialEq)]
#[command(override_usage = "rayoflight man [SUBCOMMAND] | --dir DIR")]
pub(super) struct ManFlags {
    /// The subcommand whose page to print [default: rayoflight(1)]
    // Its names are the definition's: `args::definition` gives them to
    // the argument (by its id, `MAN_SUBCOMMAND`).
    #[arg(id = MAN_SUBCOMMAND, value_name = "SUBCOMMAND")]
    pub subcommand: Option<String>,
    /// Write every page into DIR (made if missing) instead:
    /// rayoflight.1 and rayoflight-SUBCOMMAND.1.
    #[arg(long, value_name = "DIR", value_hint = ValueHint::DirPath, conflicts_with = MAN_SUBCOMMAND)]
    pub dir: Option<PathBuf>,
}

/// The id of `man`'s argument, which names a subcommand.
pub(super) const MAN_SUBCOMMAND: &str = "subcommand";

impl Subcommand for ManFlags {
    type Args = ManFlags;

    fn resolve(self, _: &clap::ArgMatches) -> Result<ManFlags, UsageError> {
        Ok(self)
    }

    /// The page on stdout; `--dir` writes files.
    fn prints(args: &ManFlags) -> bool {
        args.dir.is_none()
    }

    fn run(args: ManFlags, definition: Definition) -> Result<(), Failure> {
        let Some(dir) = args.dir else {
            let page = man_page(args.subcommand.as_deref(), definition).map_err(usage)?;
            return stdout::write(&page).map_err(Failure::Error);
        };
        files::make_folders(&dir).map_err(|e| Failure::Error(format!("{}: {e}", dir.display())))?;
        for (name, page) in man_pages(definition).map_err(Failure::Error)? {
            files::write_atomic(&dir.join(name), page.as_bytes()).map_err(fail)?;
        }
        Ok(())
    }
}

/// The completion script for `shell`.
fn completions(shell: Shell, definition: Definition) -> String {
    let mut command = definition();
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut command, "rayoflight", &mut script);
    let mut script = String::from_utf8_lossy(&script).into_owned();
    match shell {
        Shell::Bash => script.push_str(&bash_paths(definition)),
        Shell::Zsh => script = zsh_first_word(&script),
        Shell::Fish => script = fish_values(&script, definition),
        _ => {}
    }
    script
}

/// clap_complete's zsh script for a command that takes a positional
/// (the scene) and subcommands reads the first word as the scene and the
/// second as the subcommand: after `split` it offered the render's flags,
/// after `completions` the subcommands. Here the first word is either,
/// offered as both; a subcommand's words go to its own arguments, and a
/// scene's to the render's flags. Unchanged where the script is not the
/// one expected (a test fails then).
fn zsh_first_word(script: &str) -> String {
    let head = "    _arguments \"${_arguments_options[@]}\" : \\\n";
    let Some(options_at) = script.find(head).map(|at| at + head.len()) else {
        return script.to_owned();
    };
    let Some(scene_at) = script.find("'::scene -- ") else {
        return script.to_owned();
    };
    let Some(dispatch_at) = script[scene_at..]
        .find("\"*::: :->rayoflight\" \\\n")
        .map(|at| scene_at + at)
    else {
        return script.to_owned();
    };
    // A value with nothing to complete (a number, a region, PATH=VALUE):
    // nothing offered, not file names. `-o` takes its file as the next
    // word (as `-o+`, `-out` read as `-o` and `ut`), and the render's own
    // spellings `-out` and `-time` are offered.
    let free = |text: &str| text.replace(":_default' \\\n", ": ' \\\n");
    let options = format!(
        "'-out=[The image to write (also -o, --out)]:FILE:_files' \\\n\
         '-time[Print the render time (also --time)]' \\\n{}",
        free(&script[options_at..scene_at]).replace("'-o+[", "'-o[")
    );
    let mut out = String::with_capacity(script.len() + 2 * options.len() + 400);
    out.push_str(&script[..options_at]);
    out.push_str(&options);
    out.push_str("\": :->first\" \\\n");
    let rest = free(&script[dispatch_at..]);
    let rest = rest.replacen(
        "    case $state in\n    (rayoflight)\n",
        "    case $state in\n    (first)\n        \
         if (( CURRENT > 2 )); then\n            \
         # After a flag: a scene, not a subcommand.\n            \
         _files && ret=0\n        \
         else\n            \
         _alternative 'commands:command:_rayoflight_commands' \
         'scenes:scene file:_files' && ret=0\n        \
         fi\n        ;;\n    (rayoflight)\n",
        1,
    );
    let rest = rest
        .replacen("words=($line[2] ", "words=($line[1] ", 1)
        .replacen(
            "rayoflight-command-$line[2]:",
            "rayoflight-command-$line[1]:",
            1,
        )
        .replacen(
            "        case $line[2] in\n",
            "        case $line[1] in\n",
            1,
        );
    // A scene: the render's flags after it.
    let render =
        format!("(*)\n_arguments \"${{_arguments_options[@]}}\" : \\\n{options}&& ret=0\n;;\n");
    let end = "        esac\n    ;;\nesac\n";
    match rest.find(end) {
        Some(at) => {
            out.push_str(&rest[..at]);
            out.push_str(&render);
            out.push_str(&rest[at..]);
        }
        None => out.push_str(&rest),
    }
    out
}

/// clap_complete's fish script offered file names after a top-level flag
/// waiting for its value (`--method `: its test of the words before fails
/// on the flag without its value, so no flag's line applied), for a
/// subcommand's listed positional (`completions `), and after flags that
/// take a number. Here: the words before read without the flag that
/// waits; each listed positional its values; no files after a number.
fn fish_values(script: &str, definition: Definition) -> String {
    let parse =
        "    argparse -s (__fish_rayoflight_global_optspecs) -- $cmd 2>/dev/null\n    or return\n";
    let retry = "    argparse -s (__fish_rayoflight_global_optspecs) -- $cmd 2>/dev/null\n    \
                 or begin\n        \
                 # The last word, a flag waiting for its value: the words before it.\n        \
                 set -e cmd[-1]\n        \
                 argparse -s (__fish_rayoflight_global_optspecs) -- $cmd 2>/dev/null\n    \
                 end\n    or return\n";
    let mut out = script.replacen(parse, retry, 1);
    let mut root = definition();
    root.build();
    // A first word that is no subcommand is the scene: the render's
    // flags go on after it; subcommands are offered as the first word only.
    let names: Vec<&str> = root.get_subcommands().map(|s| s.get_name()).collect();
    let command = "    if set -q argv[1]\n";
    let subcommand = format!(
        "    if set -q argv[1]; and contains -- $argv[1] {}\n",
        names.join(" ")
    );
    out = out.replacen(command, &subcommand, 1);
    out = out.replace(
        "-n \"__fish_rayoflight_needs_command\" -a \"",
        "-n \"__fish_rayoflight_needs_command; and test (count (commandline -opc)) -eq 1\" -a \"",
    );
    let mut free: Vec<String> = Vec::new();
    let mut each = vec![(None, &root)];
    each.extend(root.get_subcommands().map(|s| (Some(s.get_name()), s)));
    for (name, command) in each {
        for arg in command.get_arguments().filter(|a| takes_free_value(a)) {
            if let Some(long) = arg.get_long() {
                free.push(format!(" -l {long} "));
            }
        }
        let Some(name) = name else {
            continue;
        };
        for arg in command.get_positionals() {
            let values = arg.get_value_parser().possible_values();
            let Some(values) = values else {
                continue;
            };
            let values: Vec<String> = values.map(|v| v.get_name().to_owned()).collect();
            out.push_str(&format!(
                "complete -c rayoflight -n \"__fish_rayoflight_using_subcommand {name}\" -f -a \"{}\"\n",
                values.join(" ")
            ));
        }
    }
    // No files after a flag whose value is a number, a region or
    // PATH=VALUE.
    out.lines()
        .map(|line| {
            let wants_value = line.ends_with(" -r");
            match wants_value && free.iter().any(|f| line.contains(f.as_str())) {
                true => format!("{line} -f\n"),
                false => format!("{line}\n"),
            }
        })
        .collect()
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
fn bash_paths(definition: Definition) -> String {
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
            # A subcommand's words: its flags once a dash is typed.
            {subcommands})
                [[ -z ${{cur}} ]] && COMPREPLY=( $(compgen -X '-*' -W "${{COMPREPLY[*]}}" -- '') )
                return 0
                ;;
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
fn man_pages(definition: Definition) -> Result<Vec<(String, String)>, String> {
    let names: Vec<String> = definition()
        .get_subcommands()
        .map(|s| s.get_name().to_owned())
        .collect();
    let mut pages = vec![("rayoflight.1".to_owned(), man_page(None, definition)?)];
    for name in names {
        pages.push((
            format!("rayoflight-{name}.1"),
            man_page(Some(&name), definition)?,
        ));
    }
    Ok(pages)
}

/// The man page of `subcommand` (`None`: rayoflight(1)), in roff.
fn man_page(subcommand: Option<&str>, definition: Definition) -> Result<String, String> {
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
