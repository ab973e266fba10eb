#!/usr/bin/env bash
# What `illume view`'s tests need on Debian: an X server without a screen (xvfb), Mesa's
# software Vulkan (lavapipe, in mesa-vulkan-drivers) and its loader, xdotool for input
# and ImageMagick's `import` for screenshots of the X server.
# Idempotent: apt runs only when something is missing. Runs as root (no sudo assumed).
set -euo pipefail
packages=(xvfb mesa-vulkan-drivers libvulkan1 xdotool imagemagick)
missing=()
for p in "${packages[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing+=("$p")
    fi
done
if [ ${#missing[@]} -eq 0 ]; then
    echo "viewer dependencies: all installed (${packages[*]})"
    exit 0
fi
echo "viewer dependencies: installing ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
    echo "error: installing ${missing[*]} needs root" >&2
    exit 1
fi
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y --no-install-recommends "${missing[@]}"
