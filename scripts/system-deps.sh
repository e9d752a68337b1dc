#!/usr/bin/env bash
# Debian packages the tests need: a real browser for the kiosk, and CJK fonts so that it draws
# Chinese characters (not empty boxes). Idempotent; quiet when present. Never fails the set-up:
# without root (or sudo) or outside Debian it says what is missing and why, and goes on.
set -uo pipefail
need=()
command -v chromium >/dev/null 2>&1 || need+=(chromium)
if command -v dpkg-query >/dev/null 2>&1; then
  dpkg-query -W -f='${Status}' fonts-noto-cjk 2>/dev/null | grep -q "ok installed" \
    || need+=(fonts-noto-cjk)
fi
((${#need[@]})) || exit 0
skip() { echo "system-deps: skipped installing ${need[*]}: $1 (the kiosk browser tests may skip or show empty boxes for Chinese)" >&2; exit 0; }
[[ -r /etc/debian_version ]] && command -v apt-get >/dev/null 2>&1 || skip "not a Debian system"
if [[ $(id -u) -eq 0 ]]; then
  SUDO=()
elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
  SUDO=(sudo -n)
else
  skip "not root and no password-less sudo"
fi
echo "installing Debian packages: ${need[*]}"
"${SUDO[@]}" apt-get update -qq || skip "apt-get update failed"
DEBIAN_FRONTEND=noninteractive "${SUDO[@]}" apt-get install -y -qq --no-install-recommends \
  "${need[@]}" || skip "apt-get install failed"
