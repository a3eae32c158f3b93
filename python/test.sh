#!/usr/bin/env bash
# The Python module's tests: builds the wheel with maturin in a virtual environment
# (target/venv), installs it there and runs pytest. `.ci/run` calls it after `cargo test`.
set -euo pipefail
cd "$(dirname "$0")/.."
venv=target/venv
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/pip" install -q --disable-pip-version-check -r python/requirements-test.txt
rm -f target/wheels/photon_render-*.whl
"$venv/bin/maturin" build --release -m python/Cargo.toml
"$venv/bin/pip" install -q --disable-pip-version-check --force-reinstall --no-deps target/wheels/photon_render-*.whl
cargo build --release --bin photon
(cd python && "../$venv/bin/python" -m pytest -q tests "$@")
