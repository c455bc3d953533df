#!/usr/bin/env zsh
# What zsh's completion offers for a command line, as a user's Tab would:
# an interactive zsh in a pseudo-terminal (zpty) with the completion
# system loaded from FPATH_DIR first, `compadd` wrapped to print each match
# on a line of its own. For tests/desktop/home.rs.
#
#   zsh zsh-complete.zsh FPATH_DIR 'rayoflight split --'
#
# After Valodim's zsh-capture-completion (MIT), cut to what the tests need.
zmodload zsh/zpty || exit 2
fpath_dir=$1
line=$2
zpty z zsh -f -i
init=$(mktemp)
cat > $init <<INIT
PROMPT=
fpath=($fpath_dir \$fpath)
autoload -U compinit
compinit -u -D
bindkey '^M' undefined
bindkey '^J' undefined
bindkey '^I' complete-word
null-line () { echo -E - \$'\0' }
compprefuncs=( null-line )
comppostfuncs=( null-line exit )
zstyle ':completion:*' list-grouped false
zstyle ':completion:*' insert-tab false
zstyle ':completion:*' list-separator ''
compadd () {
    if [[ \${@[1,(i)(-|--)]} == *-(O|A|D)\ * ]]; then
        builtin compadd "\$@"
        return \$?
    fi
    typeset -a __hits
    builtin compadd -A __hits "\$@"
    setopt localoptions norcexpandparam extendedglob
    typeset -A apre hpre hsuf asuf
    zparseopts -E P:=apre p:=hpre S:=asuf s:=hsuf
    [[ -n \$__hits ]] || return
    for i in {1..\$#__hits}; do
        echo -E - "\$IPREFIX\$apre\$hpre\$__hits[\$i]\$hsuf\$asuf"
    done
}
echo ok
INIT
zpty -w z "source $init"
repeat 8; do
    zpty -r z got
    [[ $got == ok* ]] && break
done
rm -f $init
zpty -w z "$line"$'\t'
integer tog=0
# Everything the pty says until the shell exits after the completion;
# the matches are between the two NUL lines.
while zpty -r z; do :; done | while IFS= read -r l; do
    if [[ $l == *$'\0\r' || $l == *$'\0' ]]; then
        (( tog++ )) && exit 0 || continue
    fi
    (( tog )) && echo -E - "${l%$'\r'}"
done
exit 0
