#!/bin/sh
# Writes the man page of a Sluice program from its --help (meson builds the
# pages with the programs and installs them in <mandir>/man1):
#
#   tools/man.sh PROGRAM NAME VERSION SUMMARY OUTPUT
#
# The page is the program's --help, then each of its commands' `--help` in
# the order its usage lists them, set verbatim: the page says what --help
# says.
set -eu
program=$1 name=$2 version=$3 summary=$4 output=$5

# the commands the program's usage lists (none for sluice-study and
# sluice-probe)
commands() {
    case $name in
    sluice)
        "$program" --help | sed -n 's/^  sluice \([a-z][a-z-]*\)\($\|[ ,]\).*/\1/p' |
            grep -vx help | awk '!seen[$0]++' ;;
    sluice-analyze)
        "$program" --help | sed -n 's/^  \([a-z][a-z0-9-]*\) .*/\1/p' ;;
    esac
}

# text as troff: backslashes and hyphens escaped, no line read as a request
verbatim() {
    sed -e 's/\\/\\e/g' -e 's/-/\\-/g' -e "s/^\\([.']\\)/\\\\\\&\\1/"
}

upper=$(printf '%s' "$name" | tr 'a-z-' 'A-Z-')
{
    printf '.TH %s 1 "" "%s %s" "User Commands"\n' "$upper" "$name" "$version"
    printf '.SH NAME\n%s \\- %s\n' "$(printf '%s' "$name" | verbatim)" "$summary"
    printf '.SH SYNOPSIS\n.nf\n'
    "$program" --help | verbatim
    printf '.fi\n'
    for command in $(commands); do
        printf '.SH "%s %s"\n.nf\n' "$(printf '%s' "$name" | verbatim)" "$command"
        "$program" "$command" --help | verbatim
        printf '.fi\n'
    done
    printf '.SH "SEE ALSO"\n'
    printf 'sluice(1), sluice\\-analyze(1), sluice\\-study(1), sluice\\-probe(1); the\n'
    printf 'documentation in share/doc/sluice under the prefix (install.md,\n'
    printf 'scene\\-format.md, analysis.md, studies.md, probe.md).\n'
} >"$output.tmp"
mv "$output.tmp" "$output"
