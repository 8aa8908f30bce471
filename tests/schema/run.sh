#!/usr/bin/env bash
# Both JSON Schemas of the config compile under ajv's strict mode, as editors and CI tools that
# use ajv compile them:
#   run.sh ARBITER SOURCE_DIR WORK_DIR
# The static schema (schema/arbiter.schema.json) and the one `arbiter schema` prints with every
# plugin on the plugin path. WORK_DIR keeps node_modules (tests/support/npm_ci.sh).
set -euo pipefail
arbiter=$1
source=$2
work=$3
. "$source/tests/support/npm_ci.sh"
npm_ci_into "$source/tests/schema" "$work" node_modules/.bin/ajv
"$arbiter" schema >"$work/extended.schema.json"
grep -q '"dds.Bridge"' "$work/extended.schema.json" || echo "note: the dds plugin is not built"
for schema in "$source/schema/arbiter.schema.json" "$work/extended.schema.json"; do
  "$work/node_modules/.bin/ajv" compile --strict=true -s "$schema"
done
