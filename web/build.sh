#!/usr/bin/env bash
# Builds the web page into web/dist/: the terrain engine compiled to WebAssembly, its JavaScript
# glue (wasm-bindgen) and the static files of web/static/. Serve it with web/serve.sh.
#
# Needs (Debian): rustc-web cargo-web rust-web-src lld-22, and wasm-bindgen-cli at the version
# of wasm-bindgen in Cargo.lock (`cargo install wasm-bindgen-cli --version X`). The native build
# keeps using the rustup toolchain: only this script uses Debian's, whose standard library source
# lets cargo build `std` for wasm32-unknown-unknown.
#
# Options: --debug (faster to build, slower to run). Environment: CARGO_TARGET_DIR (default
# target/web), WASM_BINDGEN (default: wasm-bindgen on PATH).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
profile=release
[[ "${1:-}" == "--debug" ]] && profile=debug

die() { echo "web/build.sh: $*" >&2; exit 1; }
[[ -x /usr/bin/rustc && -x /usr/bin/cargo ]] \
    || die "needs Debian's Rust with WebAssembly support: apt-get install rustc-web cargo-web rust-web-src lld-22"
command -v wasm-ld-22 >/dev/null || die "needs the WebAssembly linker: apt-get install lld-22"
wanted="$(awk '/^name = "wasm-bindgen"$/ { getline; gsub(/[^0-9.]/, ""); print; exit }' "$root/Cargo.lock")"
bindgen="${WASM_BINDGEN:-wasm-bindgen}"
have="$("$bindgen" --version 2>/dev/null | awk '{ print $2 }' || true)"
[[ "$have" == "$wanted" ]] \
    || die "needs wasm-bindgen $wanted (found: ${have:-none}): cargo install wasm-bindgen-cli --version $wanted"

target_dir="${CARGO_TARGET_DIR:-$root/target/web}"
flags=(--target wasm32-unknown-unknown -p rayterra-web -Z build-std=std,panic_abort --target-dir "$target_dir")
[[ "$profile" == release ]] && flags+=(--release)
echo "building the page ($profile) ..." >&2
(
    cd "$root"
    # Debian's cargo and rustc, never rustup's (which has no wasm32 standard library here).
    env -u RUSTUP_TOOLCHAIN RUSTC=/usr/bin/rustc RUSTDOC=/usr/bin/rustdoc RUSTC_BOOTSTRAP=1 \
        CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_LINKER=wasm-ld-22 \
        CARGO_PROFILE_RELEASE_DEBUG=false /usr/bin/cargo build "${flags[@]}"
)

dist="$here/dist"
staging="$(mktemp -d "$here/.dist.XXXXXX")"
trap 'rm -rf "$staging"' EXIT
"$bindgen" --target web --no-typescript --out-dir "$staging/pkg" \
    "$target_dir/wasm32-unknown-unknown/$profile/rayterra_web.wasm"
cp "$here"/static/* "$staging/"
# Replace the old page whole, never leaving half of one.
rm -rf "$dist.old"
[[ -d "$dist" ]] && mv "$dist" "$dist.old"
mv "$staging" "$dist"
chmod 755 "$dist"
rm -rf "$dist.old"
trap - EXIT
echo "page built in $dist ($(du -sh "$dist/pkg/rayterra_web_bg.wasm" | cut -f1) of WebAssembly); serve it with web/serve.sh" >&2
