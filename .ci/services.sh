#!/usr/bin/env bash
# Install the services the store/report tests use (PostgreSQL server binaries, headless Chromium, poppler-utils
# to read the PDF report back).
# Fresh Debian 12, run as root, non-interactive; idempotent (re-running installs nothing new).
# The tests start their own throwaway PostgreSQL cluster (initdb/pg_ctl as user `postgres`), so no
# system cluster needs to run; the default one Debian creates is stopped to free resources.
set -euo pipefail

if [ "$(id -u)" -ne 0 ]; then
    echo "services.sh: must run as root" >&2
    exit 1
fi

export DEBIAN_FRONTEND=noninteractive
packages=(postgresql chromium fonts-dejavu-core poppler-utils)

missing=()
for package in "${packages[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
        missing+=("$package")
    fi
done

if [ "${#missing[@]}" -gt 0 ]; then
    apt-get update -q
    apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# Check what the tests look for.
ls /usr/lib/postgresql/*/bin/initdb /usr/lib/postgresql/*/bin/pg_ctl >/dev/null
test -x /usr/bin/chromium
command -v pdftotext pdftoppm pdfinfo >/dev/null
id postgres >/dev/null

# The tests bring their own cluster; a running default cluster is not needed.
if command -v pg_ctlcluster >/dev/null && pg_lsclusters -h 2>/dev/null | grep -q online; then
    pg_lsclusters -h | awk '$4 == "online" {print $1, $2}' | while read -r version cluster; do
        pg_ctlcluster "$version" "$cluster" stop || true
    done
fi

echo "services.sh: postgresql $(ls /usr/lib/postgresql) and $(/usr/bin/chromium --version 2>/dev/null || echo chromium) ready"
