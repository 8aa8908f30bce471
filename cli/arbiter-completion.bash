# Bash completion for `arbiter`: commands, options, option values, config files, and the layer
# and behaviour names of the config on the command line (read with `arbiter dump`).
# Installed as PREFIX/share/bash-completion/completions/arbiter, where bash-completion finds it
# for PREFIX /usr, /usr/local or ~/.local; for another PREFIX, see docs/cli.md ("Bash
# completion"). To try it from the sources:
#   source cli/arbiter-completion.bash

_arbiter_config_of() {  # the first config file among the words typed so far
  local word
  for word in "${COMP_WORDS[@]:2:COMP_CWORD-2}"; do
    case "$word" in
      *.yaml | *.yml | *.json) [[ -f $word ]] && { printf '%s\n' "$word"; return; } ;;
    esac
  done
}

_arbiter_files() {  # files whose names match the regex $1, and directories, completing $cur
  compgen -f -- "$cur" | grep -E -- "$1"
  compgen -d -- "$cur"
}

_arbiter_plugin_paths() {  # the --plugin-path options typed so far, for `arbiter dump`
  local i word
  for ((i = 1; i < COMP_CWORD; ++i)); do
    word=${COMP_WORDS[i]}
    case "$word" in
      --plugin-path) printf '%s\n' "--plugin-path" "${COMP_WORDS[i + 1]}"; ((++i)) ;;
      --plugin-path=*) printf '%s\n' "$word" ;;
    esac
  done
}

# layers|behaviours|machines of a config, from its text dump. A behaviour is offered by its name,
# and as LAYER/NAME only when its name is in several layers or the word typed has a '/'.
_arbiter_names() {
  local config what=$1 plugin_paths
  config=$(_arbiter_config_of)
  [[ -n $config ]] || return
  mapfile -t plugin_paths < <(_arbiter_plugin_paths)
  "${COMP_WORDS[0]}" "${plugin_paths[@]}" dump "$config" 2>/dev/null |
    awk -v what="$what" -v qualified="$([[ $cur == */* ]] && echo 1)" '
    /^layer / { layer = $2; if (what == "layers") print $2 }
    /^state machine / { if (what == "machines") print $3 }
    /^    [0-9]+\. / { if (what == "behaviours") { layers[$2]++; full[++n] = layer "/" $2; name[n] = $2 } }
    END {
      for (i = 1; i <= n; ++i) print (qualified || layers[name[i]] > 1) ? full[i] : name[i]
    }'
}

_arbiter() {
  local cur prev command word i
  cur=${COMP_WORDS[COMP_CWORD]}
  prev=${COMP_WORDS[COMP_CWORD - 1]}
  local commands="validate run dump explain seek test plugins schema view edit plot replay diff lsp new"
  local global="--help --version --log-level --plugin-path --max-file-bytes --color"
  local global_after="--log-level --plugin-path --max-file-bytes --color"  # after the command

  command=""
  for ((i = 1; i < COMP_CWORD; ++i)); do
    word=${COMP_WORDS[i]}
    case "$word" in
      --log-level | --plugin-path | --max-file-bytes | --color) ((++i)) ;;
      -*) ;;
      *) command=$word; break ;;
    esac
  done

  case "$prev" in
    --log-level) mapfile -t COMPREPLY < <(compgen -W "trace debug info warn error off" -- "$cur"); return ;;
    --plugin-path) mapfile -t COMPREPLY < <(compgen -d -- "$cur"); return ;;
    --color) mapfile -t COMPREPLY < <(compgen -W "auto always never" -- "$cur"); return ;;
    --format)
      case "$command" in
        dump) mapfile -t COMPREPLY < <(compgen -W "text dot json" -- "$cur") ;;
        *) mapfile -t COMPREPLY < <(compgen -W "text json" -- "$cur") ;;
      esac
      return ;;
    --trace)
      case "$command" in
        explain | seek | view) mapfile -t COMPREPLY < <(_arbiter_files '\.(jsonl|mcap)$') ;;
        *) mapfile -t COMPREPLY < <(_arbiter_files '\.jsonl$') ;;
      esac
      return ;;
    --record) mapfile -t COMPREPLY < <(_arbiter_files '\.mcap$'); return ;;
    --compare) mapfile -t COMPREPLY < <(_arbiter_files '\.(jsonl|mcap)$'); return ;;
    --config | --inputs) mapfile -t COMPREPLY < <(_arbiter_files '\.(yaml|yml|json)$'); return ;;
    --tolerance) return ;;
    --layer) mapfile -t COMPREPLY < <(compgen -W "$(_arbiter_names layers)" -- "$cur"); return ;;
    --steps | --step | --from | --break | --load | --serve | --serve-token | --foxglove | --rt-priority | --record-flush) return ;;
    --junit) mapfile -t COMPREPLY < <(_arbiter_files '\.xml$'); return ;;
    --output | -o) mapfile -t COMPREPLY < <(_arbiter_files '\.svg$'); return ;;
  esac

  if [[ -z $command ]]; then
    if [[ $cur == -* ]]; then
      mapfile -t COMPREPLY < <(compgen -W "$global" -- "$cur")
    else
      mapfile -t COMPREPLY < <(compgen -W "$commands" -- "$cur")
    fi
    return
  fi

  local options
  case "$command" in
    validate) options="--format --strict --help" ;;
    run) options="--steps --trace --inputs --record --record-flush --quiet --realtime --strict --serve --foxglove --paused --watch --serve-token --serve-readonly --rt-priority --full-speed --edit --break --help" ;;
    dump) options="--format --layer --help" ;;
    explain) options="--trace --step --help" ;;
    seek) options="--trace --from --help" ;;
    test) options="--junit --tolerance --help" ;;
    view) options="--trace --serve --step --compare --help" ;;
    edit) options="--serve --serve-token --help" ;;
    plot) options="--output --actuators --compare --help" ;;
    replay) options="--config --trace --record --record-flush --foxglove --steps --help" ;;
    diff) options="--tolerance --format --help" ;;
    plugins) options="--format --load --builtin --help" ;;
    schema) options="--load --builtin --help" ;;
    lsp) options="--help" ;;
    new) options="--help" ;;
  esac
  if [[ $cur == -* ]]; then
    # Global options may follow the command too (`arbiter run FILE --plugin-path DIR`).
    mapfile -t COMPREPLY < <(compgen -W "$options $global_after" -- "$cur")
    return
  fi
  case "$command" in
    plugins | schema | lsp) return ;;
    new)
      # `new plugin NAME [DIR]`: the kind of project, then a name to type, then a directory.
      local after=()
      for ((i = i + 1; i < COMP_CWORD; ++i)); do
        case "${COMP_WORDS[i]}" in
          --log-level | --plugin-path | --max-file-bytes | --color) ((++i)) ;;
          -*) ;;
          *) after+=("${COMP_WORDS[i]}") ;;
        esac
      done
      case ${#after[@]} in
        0) mapfile -t COMPREPLY < <(compgen -W "plugin" -- "$cur") ;;
        2) mapfile -t COMPREPLY < <(compgen -d -- "$cur") ;;
      esac
      return ;;
    plot | diff)
      mapfile -t COMPREPLY < <(_arbiter_files '\.(jsonl|mcap)$')
      return ;;
    replay)
      mapfile -t COMPREPLY < <(_arbiter_files '\.mcap$')
      return ;;
    test)
      mapfile -t COMPREPLY < <(_arbiter_files '\.test\.(yaml|yml|json)$')
      return ;;
    explain)
      if [[ -n $(_arbiter_config_of) ]]; then
        mapfile -t COMPREPLY < <(compgen -W "$(_arbiter_names behaviours) $(_arbiter_names machines)" -- "$cur")
        return
      fi ;;
  esac
  mapfile -t COMPREPLY < <(_arbiter_files '\.(yaml|yml|json)$')
}

complete -o filenames -F _arbiter arbiter
