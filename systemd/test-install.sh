#!/usr/bin/env bash
# An install that starts: `cmake --install` of a built tree into a temporary prefix, and into
# DESTDIR with the prefixes /usr and /usr/local. Checks that every file lands inside them (the
# manifest, the tree, and the places the old install wrote to), that the tree holds what an
# install needs (programs, unit, sysusers entry, configuration with drivers.json, the whole
# documentation, man pages, bash completion), that the unit's ExecStart and --config are the
# installed files and it passes systemd-analyze verify, that the installed programs print the
# version and probe reads the installed daemon config, and that a re-install keeps an edited
# configuration file. Usage: test-install.sh BUILD_DIR PROJECT_VERSION
set -euo pipefail
build=$(cd "$1" && pwd) version=$2
here=$(cd "$(dirname "$0")" && pwd)
source_dir=$(dirname "$here")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() {
  echo "FAIL: $*" >&2
  exit 1
}

# Where the install used to write whatever the prefix: none of these may appear.
outside=(/etc/robocald /usr/local/etc/robocald /usr/lib/systemd/system/robocald.service
  /usr/local/lib/systemd/system/robocald.service /usr/share/doc/robocal /usr/local/share/doc/robocal)
existed=()
for p in "${outside[@]}"; do [ -e "$p" ] && existed+=("$p"); done

# install_into DESTDIR PREFIX: installs, then checks that every file the manifest lists (paths
# without DESTDIR) is inside DESTDIR, or PREFIX without it, and that the install made no file
# there the manifest misses.
install_into() {
  local destdir=$1 prefix=$2 root
  root=${destdir:-$prefix}
  mkdir -p "$root"
  find "$root" -type f | sort >"$tmp/before"
  DESTDIR=$destdir cmake --install "$build" --prefix "$prefix" >"$tmp/install.log" 2>&1 ||
    { cat "$tmp/install.log"; fail "cmake --install --prefix $prefix (DESTDIR=$destdir) failed"; }
  sed "s#^#$destdir#" "$build/install_manifest.txt" >"$tmp/manifest"
  while IFS= read -r f; do
    case $f in
      "$root"/*) ;;
      *) fail "installed outside $root: $f" ;;
    esac
    [ -f "$f" ] || fail "in the manifest but not installed: $f"
  done <"$tmp/manifest"
  sort -u "$tmp/before" "$tmp/manifest" >"$tmp/known"
  unlisted=$(find "$root" -type f | sort | comm -23 - "$tmp/known")
  [ -z "$unlisted" ] || fail "the install made files its manifest does not list: $unlisted"
  for p in "${outside[@]}"; do
    if [ -e "$p" ] && [[ ! " ${existed[*]-} " == *" $p "* ]]; then fail "the install wrote $p"; fi
  done
}

# check_tree DESTDIR PREFIX SYSCONFDIR: the installed tree for that prefix.
check_tree() {
  local d=$1 prefix=$2 sysconf=$3
  local unit=$d$prefix/lib/systemd/system/robocald.service docdir=$d$prefix/share/doc/robocal
  for f in "$d$prefix/bin/robocal" "$d$prefix/sbin/robocald" "$d$prefix/bin/robocal-cellsim"; do
    [ -x "$f" ] || fail "no program $f"
  done
  for f in "$unit" "$d$prefix/lib/sysusers.d/robocald.conf" "$docdir/README.md" \
    "$d$prefix/share/man/man1/robocal.1" "$d$prefix/share/man/man8/robocald.8" \
    "$d$prefix/share/bash-completion/completions/robocal"; do
    [ -s "$f" ] || fail "not installed: $f"
  done
  for name in robocald.json drivers.json puma560.json cell.json; do
    cmp -s "$source_dir/config/$name" "$d$sysconf/robocald/$name" ||
      fail "not installed as shipped: $d$sysconf/robocald/$name"
  done
  # The whole documentation, in the repository's layout, so `docs/NAME.md` references resolve.
  while IFS= read -r -d '' f; do
    rel=${f#"$source_dir"/docs/}
    cmp -s "$f" "$docdir/docs/$rel" || fail "documentation not installed: $docdir/docs/$rel"
  done < <(find "$source_dir/docs" -type f -print0)
  # shellcheck disable=SC2016 # the backquotes are the docs' own
  grep -ho '`docs/[A-Za-z0-9_.-]*\.md`' "$docdir/README.md" "$docdir"/docs/*.md | sort -u |
    while read -r ref; do
      ref=${ref//\`/}
      [ -f "$docdir/$ref" ] || fail "installed documentation refers to $ref, not installed"
    done
  # The sysusers entry makes the operators' group, and the unit runs the daemon in it.
  grep -q '^g robocal ' "$d$prefix/lib/sysusers.d/robocald.conf" || fail "no robocal group in sysusers"
  mkdir -p "$tmp/sysroot/etc"
  systemd-sysusers --root="$tmp/sysroot" --dry-run "$d$prefix/lib/sysusers.d/robocald.conf" \
    >"$tmp/sysusers.log" 2>&1 || { cat "$tmp/sysusers.log"; fail "systemd-sysusers refuses the entry"; }
  grep -qx 'Group=robocal' "$unit" || fail "the unit does not run in the robocal group"

  # The unit points at the installed program and configuration, and at the installed docs.
  local exec_start="ExecStart=$prefix/sbin/robocald --config $sysconf/robocald/robocald.json"
  grep -qxF "$exec_start" "$unit" || fail "$unit: expected '$exec_start', got '$(grep ^ExecStart= "$unit")'"
  local doc="Documentation=man:robocald(8) file:$prefix/share/doc/robocal/docs/robocald.md"
  grep -qxF "$doc" "$unit" || fail "$unit: expected '$doc'"
  if grep -n '@[A-Z_]*@' "$unit"; then fail "$unit: template placeholders left"; fi
  "$here/verify-unit.sh" "$unit" "$d$prefix/sbin/robocald" "$d$prefix/share/man" ||
    fail "$unit does not verify"

  # The programs run from the install and say their version.
  [ "$("$d$prefix/bin/robocal" --version)" = "robocal $version" ] || fail "robocal --version"
  [ "$("$d$prefix/sbin/robocald" --version)" = "robocald $version" ] || fail "robocald --version"
  # probe reads the installed daemon config's drivers section (ports given here: none exist).
  local code=0 out
  out=$("$d$prefix/bin/robocal" probe --config "$d$sysconf/robocald/robocald.json" \
    --val "$tmp/no-such-tty" --bar "$tmp/no-such-tty" --seconds 0 2>&1) || code=$?
  if [ "$code" != 1 ] || [[ $out != *"PROBLEM (no port)"* ]]; then
    fail "probe with the installed robocald.json (exit $code): $out"
  fi

  # The man pages: every command of robocal has its section, and groff finds nothing wrong.
  local man1=$d$prefix/share/man/man1/robocal.1 man8=$d$prefix/share/man/man8/robocald.8
  for command in $("$d$prefix/bin/robocal" help | sed -n 's/^  \([a-z][a-z0-9-]*\) .*/\1/p'); do
    grep -qx "\.SS $command" "$man1" || fail "robocal.1 has no section for $command"
  done
  grep -q '^\.TH ROBOCALD 8 .*robocald '"$version" "$man8" || fail "robocald.8 has no header"
  if command -v groff >/dev/null; then
    for page in "$man1" "$man8"; do
      warnings=$(groff -man -Tutf8 -ww -z "$page" 2>&1)
      [ -z "$warnings" ] || fail "groff on $page: $warnings"
    done
  fi
  # The completion offers the commands, then each command's options.
  local completion=$d$prefix/share/bash-completion/completions/robocal
  complete_words() {
    bash -c 'source "$1"; shift; COMP_WORDS=("$@"); COMP_CWORD=$(($# - 1)); _robocal
             echo "${COMPREPLY[*]-}"' _ "$completion" "$@"
  }
  [ "$(complete_words robocal pro)" = probe ] || fail "completion of 'robocal pro'"
  [ "$(complete_words robocal --ver)" = --version ] || fail "completion of 'robocal --ver'"
  [ "$(complete_words robocal probe --con)" = --config ] || fail "completion of 'robocal probe --con'"
  [[ " $(complete_words robocal solve --) " == *" --report "* ]] || fail "completion of 'robocal solve --'"
}

# A prefix of one's own, without DESTDIR: configuration in PREFIX/etc.
install_into "" "$tmp/prefix"
check_tree "" "$tmp/prefix" "$tmp/prefix/etc"
echo "install --prefix $tmp/prefix: ok"

# Packaging: DESTDIR with the system prefixes (/usr puts the configuration in /etc).
install_into "$tmp/dest-usr" /usr
check_tree "$tmp/dest-usr" /usr /etc
install_into "$tmp/dest-local" /usr/local
check_tree "$tmp/dest-local" /usr/local /usr/local/etc
echo "install DESTDIR=... --prefix /usr and /usr/local: ok"

# A re-install keeps an operator's edited configuration and puts the new default beside it.
config=$tmp/dest-usr/etc/robocald/robocald.json
sed -i 's/"port": 7687/"port": 7688/' "$config"
cp "$config" "$tmp/edited.json"
install_into "$tmp/dest-usr" /usr
cmp -s "$config" "$tmp/edited.json" || fail "the re-install overwrote the edited $config"
cmp -s "$config.new" "$source_dir/config/robocald.json" || fail "no $config.new with the new default"
cmp -s "$tmp/dest-usr/etc/robocald/cell.json" "$source_dir/config/cell.json" || fail "cell.json"
echo "re-install keeps the edited robocald.json: ok"
