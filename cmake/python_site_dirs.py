"""Prints the folders the interpreter that runs it imports installed packages from, one a line,
as real paths, the default scheme's own first (Debian's python3: /usr/local/lib/python3.11/
dist-packages; a venv's: <venv>/lib/python3.11/site-packages): python/CMakeLists.txt installs
the package into the first of them under the install prefix, and says so."""

import os
import site
import sysconfig

folders = [sysconfig.get_path("platlib"), sysconfig.get_path("purelib"), *site.getsitepackages()]
if site.ENABLE_USER_SITE:
    folders.append(site.getusersitepackages())
seen = []
for folder in map(os.path.realpath, folders):
    if folder not in seen:
        seen.append(folder)
print("\n".join(seen))
