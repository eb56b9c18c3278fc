#!/usr/bin/env bash
# Checks that every file the documentation points at exists inside this repository, so the
# docs stand on their own in a fresh clone. Looks at README.md and docs/*.md:
#   - markdown links [text](target): relative targets must exist (resolved from the file's folder);
#   - paths in backticks that start with a top-level folder of the repository (`docs/x.md`,
#     `config/cell.json`, `daemon/src/run.cpp`): must exist (resolved from the repository root);
#   - any reference that leaves the repository (`../...`) is an error.
# Backticked paths with placeholders (<name>, {x}, *) are skipped. Prints each broken reference
# as FILE:LINE: TARGET and exits 1 if there is any, 0 otherwise.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

# Top-level folders of the repository (what a backticked repository path starts with).
tops=()
for d in */; do
  d=${d%/}
  case $d in build | build-* | out) continue ;; esac
  tops+=("$d")
done
top_re="^($(IFS='|'; echo "${tops[*]}"))/"

files=(README.md docs/*.md)
broken=0
report() {
  echo "$1:$2: $3"
  broken=$((broken + 1))
}

for f in "${files[@]}"; do
  dir=$(dirname "$f")
  # Markdown links: [text](target "title"), targets without a scheme or a leading '#'.
  while IFS=: read -r n target; do
    [[ -z $target ]] && continue
    target=${target#](}
    target=${target%)}
    target=${target%% *}
    case $target in http://* | https://* | mailto:* | '#'*) continue ;; esac
    path=${target%%#*}
    if [[ $path == /* ]]; then
      report "$f" "$n" "$target (absolute path)"
    elif [[ $(realpath -m "$dir/$path") != "$root"/* ]]; then
      report "$f" "$n" "$target (outside the repository)"
    elif [[ ! -e $dir/$path ]]; then
      report "$f" "$n" "$target"
    fi
  done < <(grep -no '\]([^)]*)' "$f" || true)
  # Backticked paths.
  while IFS=: read -r n token; do
    token=${token//\`/}
    [[ -z $token ]] && continue
    case $token in *'<'* | *'{'* | *'*'* | *'$'*) continue ;; esac
    path=${token#./}
    path=${path%%#*}
    if [[ $path == ../* ]]; then
      report "$f" "$n" "$token (outside the repository)"
    elif [[ $path =~ $top_re ]] && [[ ! -e $path ]]; then
      report "$f" "$n" "$token"
    fi
  done < <(grep -no '`[^` ]*`' "$f" || true)
done

if ((broken > 0)); then
  echo "check-doc-links: $broken broken reference(s) in ${#files[@]} files" >&2
  exit 1
fi
echo "check-doc-links: every reference in ${#files[@]} files resolves inside the repository"
