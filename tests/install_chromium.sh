#!/bin/sh
# Debian's chromium for the browser tests (the tests drive /usr/bin/chromium with Playwright;
# Playwright's own browser download is never used).
set -e
if [ -x /usr/bin/chromium ]; then
    exit 0
fi
if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
    exit 0
fi
echo "tests/install_chromium.sh: /usr/bin/chromium is missing and this is not root:" \
     "run 'sudo apt-get install chromium' for the browser tests (they skip without it," \
     "and fail when CI is set)." >&2
