#!/bin/sh
# Prints one code block of a Markdown file: the fenced block right after the line
#
#   <!-- snippet: NAME -->
#
# The quick starts of README.md carry such markers, and the tests run exactly what the README
# shows: cpp_examples/readme_quickstarts.sh (ctest readme_quickstarts: the C, C++ and PCL
# programs and their build lines), cli/tests/readme.rs (the command-line quick start and
# install) and python/tests/test_readme.py (the Python quick start). The Rust blocks are
# doctests (src/lib.rs). Editing a marked block changes what is tested; removing a marker, or
# marking two blocks with one name, fails the test that asks for it.
#
# Usage: scripts/readme-snippet.sh FILE NAME     (the block's lines on stdout, without fences)
# Exit status 1, with a message on stderr, when NAME marks no block, more than one block, or a
# line that is not an opening fence, or when the block is not closed.
set -eu
if [ "$#" -ne 2 ]; then
    echo "usage: $0 FILE NAME" >&2
    exit 2
fi
awk -v name="$2" -v file="$1" '
    function fail(msg) { print file ": snippet \"" name "\": " msg > "/dev/stderr"; failed = 1; exit 1 }
    $0 == "<!-- snippet: " name " -->" {
        if (++marks > 1) fail("marked twice (lines " first " and " NR ")")
        first = NR; state = "fence"; next
    }
    state == "fence" {
        if ($0 !~ /^```[A-Za-z0-9_+-]*$/) fail("line " NR " after the marker is not an opening fence")
        state = "body"; next
    }
    state == "body" && $0 == "```" { state = "done"; next }
    state == "body" { body = body $0 "\n" }
    END {
        if (failed) exit 1
        if (marks == 0) fail("no line <!-- snippet: " name " -->")
        if (state != "done") fail("the block after line " first " is not closed")
        printf "%s", body
    }
' "$1"
