#!/usr/bin/env bash
# Checks that building one member (`cargo test -p CRATE`) gives every dependency the features it
# gets in a whole-workspace build, so the two share one build (see crates/workspace-hack).
# Prints each dependency whose features differ and exits 1 when there is one.
set -euo pipefail
cd "$(dirname "$0")/.."
features() {
    cargo tree "$@" -e normal,build,dev -f '{p} [{f}]' --prefix none --no-dedupe | sed 's/ (\*)//' | sort -u
}
workspace=$(mktemp)
trap 'rm -f "$workspace"' EXIT
features --workspace > "$workspace"
status=0
for member in raytracer terrain rayterra atomic-file; do
    differences=$(comm -23 <(features -p "$member") "$workspace")
    while IFS= read -r line; do
        [ -n "$line" ] || continue
        package=${line% \[*}
        echo "$member: $line; the workspace: $(grep -F "$package [" "$workspace" | sed 's/.* \[/[/')"
        status=1
    done <<< "$differences"
done
[ "$status" = 0 ] && echo "every member builds its dependencies with the workspace's features"
exit "$status"
