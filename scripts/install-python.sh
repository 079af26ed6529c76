#!/usr/bin/env bash
# Installs the Python module of a build tree (configured with -DTEXGRAD_BUILD_PYTHON=ON) so that
# `python3 -c "import texgrad"` works: scripts/install-python.sh BUILD (as root).
#
# The module is built for Debian's /usr/bin/python3 (python3-dev headers; numpy and scipy are
# Debian packages) and `cmake --install BUILD --component python` puts it into that interpreter's
# site folder (/usr/local/lib/python3.X/dist-packages). When the `python3` found first on PATH is
# another interpreter of the same major.minor version (e.g. pyenv's CPython 3.11.7 on top of
# Debian's 3.11.2: same ABI), the package is copied into its site-packages too, and if it cannot
# import numpy, a .pth file adds Debian's /usr/lib/python3/dist-packages (numpy, scipy,
# matplotlib) to its path. Another version cannot load the module: use /usr/bin/python3 then.
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:?usage: scripts/install-python.sh BUILD}"
cmake --install "$build" --component python >/dev/null
debian=/usr/bin/python3
package="$(cd / && "$debian" -c 'import os, texgrad; print(os.path.dirname(texgrad.__file__))')"
echo "texgrad $("$debian" -c 'import texgrad; print(texgrad.__version__)') installed for $debian in $package"

other="$(command -v python3)"
same="$(cd / && "$other" -c 'import sys; print(sys.executable)')"
[[ "$same" == "$("$debian" -c 'import sys; print(sys.executable)')" ]] && exit 0
version() { "$1" -c 'import sys; print("%d.%d" % sys.version_info[:2])'; }
if [[ "$(version "$other")" != "$(version "$debian")" ]]; then
  echo "note: $other is Python $(version "$other"), the module is built for $(version "$debian"): use $debian"
  exit 0
fi
site="$(cd / && "$other" -c 'import sysconfig; print(sysconfig.get_paths()["platlib"])')"
mkdir -p "$site"
rm -rf "$site/texgrad"
cp -r "$package" "$site/texgrad"
if ! (cd / && "$other" -c 'import numpy' 2>/dev/null); then
  echo /usr/lib/python3/dist-packages >"$site/texgrad-debian-dist-packages.pth"
fi
echo "texgrad $(cd / && "$other" -c 'import texgrad; print(texgrad.__version__)') installed for $other in $site/texgrad"
