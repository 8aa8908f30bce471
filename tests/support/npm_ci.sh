# Sourced by the node-driven tests' run.sh scripts (web/tests, tests/lsp, tests/mcap, tests/schema).
# npm_ci_into PACKAGE_DIR WORK_DIR INSTALLED: installs PACKAGE_DIR's pinned packages into WORK_DIR
# (under the build directory), which keeps node_modules between runs: `npm ci` runs only when
# package-lock.json changed or INSTALLED (a path under WORK_DIR) is missing, so a second run
# downloads nothing.
npm_ci_into() {
  local package=$1 work=$2 installed=$3
  mkdir -p "$work"
  if ! cmp -s "$package/package-lock.json" "$work/package-lock.json" || [[ ! -e $work/$installed ]]; then
    cp "$package/package.json" "$package/package-lock.json" "$work/"
    (cd "$work" && npm ci --no-audit --no-fund --loglevel=error)
  fi
}
