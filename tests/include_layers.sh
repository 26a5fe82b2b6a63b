#!/usr/bin/env bash
# The include rule of src/ as a test: a folder is a layer, and a file may include (with
# `#include "layer/file.h"`) headers of its own layer and of layers below it, never above it or
# beside it. Fails naming each offending file and line. Usage: include_layers.sh SRC_DIR
set -u
src="${1:?usage: include_layers.sh SRC_DIR}"

# Lowest first; layers on one line share a level and may not include each other.
layers=(
  "core"
  "texture"
  "geometry"
  "accel"
  "materials"
  "scene"
  "validation"
  "integrators"
  "io"
  "render"
  "view"
  "app api"
)
# Known exceptions, as "file -> included header" (none today).
exceptions=()

declare -A level
for i in "${!layers[@]}"; do
  for l in ${layers[$i]}; do level[$l]=$i; done
done

order=""
for i in "${!layers[@]}"; do order+="${order:+ < }${layers[$i]// /|}"; done

bad=0
while IFS= read -r file; do
  rel="${file#"$src"/}"
  from="${rel%%/*}"
  if [ -z "${level[$from]+x}" ]; then
    echo "$rel: folder '$from' is not a known layer"
    bad=1
    continue
  fi
  while IFS=: read -r line target; do
    to="${target%%/*}"
    [ "$to" = "$from" ] && continue
    for e in "${exceptions[@]}"; do
      [ "$e" = "$rel -> $target" ] && continue 2
    done
    if [ -z "${level[$to]+x}" ]; then
      echo "$rel:$line: includes \"$target\" from '$to', which is not a known layer"
      bad=1
    elif [ "${level[$to]}" -ge "${level[$from]}" ]; then
      echo "$rel:$line: includes \"$target\": layer '$from' may not include layer '$to'"
      bad=1
    fi
  done < <(grep -n '^[[:space:]]*#[[:space:]]*include[[:space:]]*"' "$file" |
           sed -E 's/^([0-9]+):[[:space:]]*#[[:space:]]*include[[:space:]]*"([^"]*)".*/\1:\2/')
done < <(find "$src" -mindepth 2 \( -name '*.h' -o -name '*.cpp' -o -name '*.in' \) -not -path "$src/cmake/*" | sort)

if [ $bad -ne 0 ]; then
  echo "include rule broken; layers, lowest first (a layer includes only itself and those before it):"
  echo "  $order"
  exit 1
fi
echo "include rule holds: $order"
