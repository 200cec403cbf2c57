#!/usr/bin/env bash
# Builds the nbhd library for release and installs it into PREFIX for C and C++ users, in the
# layout cargo-c gives a crate's C library (headers in a subdirectory named after the library,
# versioned shared library with SONAME links, pkg-config file), plus a CMake package:
#
#   PREFIX/include/nbhd/nbhd.h      the C API (found as <nbhd.h>: the CMake package and the
#   PREFIX/include/nbhd/nbhd.hpp    pkg-config files put PREFIX/include/nbhd on the include path)
#                                   and the C++ RAII layer over it (<nbhd.hpp>, header-only)
#   PREFIX/include/nbhd/nbhd_pcl.hpp  nbhd::PclSearch, a pcl::search::Search backend
#                                   (<nbhd_pcl.hpp>, header-only; the program links PCL)
#   PREFIX/lib/libnbhd.so.X.Y.Z   the shared library, version X.Y.Z of Cargo.toml
#   PREFIX/lib/libnbhd.so.0.Y     -> libnbhd.so.X.Y.Z: the SONAME, the name programs record
#                                    (libnbhd.so.X from version 1.0 on; see below)
#   PREFIX/lib/libnbhd.so         -> the SONAME link: the name the linker finds for -lnbhd
#   PREFIX/lib/libnbhd.a          the static library
#   PREFIX/lib/cmake/nbhd/nbhdConfig.cmake, nbhdConfigVersion.cmake
#       find_package(nbhd CONFIG REQUIRED) gives nbhd::nbhd (shared library) and
#       nbhd::nbhd_static (static library plus the system libraries Rust's std needs)
#   PREFIX/lib/pkgconfig/nbhd.pc
#       pkg-config --cflags --libs nbhd            (shared)
#       pkg-config --static --cflags --libs nbhd   (shared, plus the static library's needs)
#   PREFIX/lib/pkgconfig/nbhd-static.pc
#       pkg-config --cflags --libs nbhd-static     (libnbhd.a by path, and the system libraries)
#
# The SONAME (set by build.rs when cargo links the library, checked here) follows the ABI
# rule: libnbhd.so.MAJOR from version 1.0 on, and libnbhd.so.0.MINOR for 0.x, whose minor
# releases may break the ABI as Cargo's semver rules allow. A patch release keeps the SONAME, so
# programs linked against an older patch release load the newer one.
#
# The installed files are relocatable: the CMake config and the .pc file locate the prefix from
# their own place, so the prefix directory may be moved after installation.
#
# Release-grade by default: the libraries are built with Cargo's `dist` profile (Cargo.toml: the
# release profile's code without debug information, the shared library's symbol table stripped;
# its exported nbhd_* symbols stay), and the static library's debug sections, which come with
# Rust's standard library, are removed with `strip --strip-debug`. To keep symbols and line
# tables (profiling, debugging a crash inside nbhd), install the `release` profile unstripped:
#
#   NBHD_KEEP_SYMBOLS=1 scripts/install.sh PREFIX
#
# Usage: scripts/install.sh PREFIX     (PREFIX relative to the current directory, or absolute)
set -euo pipefail

if [ "$#" -ne 1 ] || [ -z "$1" ]; then
    echo "usage: $0 PREFIX" >&2
    exit 2
fi
mkdir -p "$1"
prefix="$(cd "$1" && pwd)"
repo="$(cd "$(dirname "$0")/.." && pwd)"
cd "$repo"

# Version of the [package] section of Cargo.toml (the nbhd crate, not a dependency).
version="$(awk '
    /^\[/ { in_pkg = ($0 == "[package]") }
    in_pkg && /^version[ \t]*=/ { gsub(/.*=[ \t]*"|".*/, ""); print; exit }
' Cargo.toml)"
if ! [[ "$version" =~ ^[0-9]+\.[0-9]+\.[0-9]+ ]]; then
    echo "install.sh: cannot read the package version from Cargo.toml (got '$version')" >&2
    exit 1
fi
if ! grep -q "^#define NBHD_VERSION_MAJOR ${version%%.*}\$" include/nbhd.h; then
    echo "install.sh: include/nbhd.h does not match version $version of Cargo.toml" >&2
    exit 1
fi
IFS=. read -r v_major v_minor v_patch <<<"${version%%[-+]*}"
# The rule of build.rs (see the top of this file).
if [ "$v_major" = 0 ]; then
    soname="libnbhd.so.0.$v_minor"
else
    soname="libnbhd.so.$v_major"
fi
real_name="libnbhd.so.$v_major.$v_minor.$v_patch"

keep_symbols="${NBHD_KEEP_SYMBOLS:-0}"
case "$keep_symbols" in
    0 | "") keep_symbols=0; profile=dist ;;
    1) profile=release ;;
    *) echo "install.sh: NBHD_KEEP_SYMBOLS must be 0 or 1 (got '$keep_symbols')" >&2; exit 2 ;;
esac
if [ "$keep_symbols" = 0 ] && ! command -v strip >/dev/null 2>&1; then
    echo "install.sh: strip (binutils) is missing; install it, or set NBHD_KEEP_SYMBOLS=1" >&2
    exit 1
fi

echo "== building nbhd $version (cargo build --profile $profile --lib)"
cargo build --profile "$profile" --lib -p nbhd
target_dir="${CARGO_TARGET_DIR:-$repo/target}"
case "$target_dir" in /*) ;; *) target_dir="$repo/$target_dir" ;; esac
release="$target_dir/$profile"
for f in libnbhd.so libnbhd.a; do
    [ -f "$release/$f" ] || { echo "install.sh: $release/$f was not built" >&2; exit 1; }
done
# The links below are only right if the library carries exactly this SONAME.
if command -v readelf >/dev/null 2>&1; then
    built_soname="$(readelf -d "$release/libnbhd.so" | sed -n 's/.*(SONAME).*\[\(.*\)\].*/\1/p')"
    if [ "$built_soname" != "$soname" ]; then
        echo "install.sh: $release/libnbhd.so has SONAME '$built_soname', expected '$soname' (build.rs)" >&2
        exit 1
    fi
else
    echo "install.sh: readelf not found (binutils); not checking that the SONAME is $soname" >&2
fi

# System libraries the static library needs on Linux: those Rust's std links
# (`cargo rustc --release -- --print native-static-libs` lists them; computing them here would
# rebuild the crate with different flags, so they are written down, and the C++ examples' ctest
# links a program against nbhd::nbhd_static to prove the list complete).
static_deps_cmake="Threads::Threads;\${CMAKE_DL_LIBS};m;rt;util;gcc_s"
static_deps_pc="-lgcc_s -lutil -lrt -lpthread -lm -ldl -lc"

echo "== installing into $prefix"
install -d "$prefix/include/nbhd" "$prefix/lib/cmake/nbhd" "$prefix/lib/pkgconfig"
install -m 644 include/nbhd.h include/nbhd.hpp include/nbhd_pcl.hpp "$prefix/include/nbhd/"
install -m 755 "$release/libnbhd.so" "$prefix/lib/$real_name"
ln -sfn "$real_name" "$prefix/lib/$soname"
ln -sfn "$soname" "$prefix/lib/libnbhd.so"
install -m 644 "$release/libnbhd.a" "$prefix/lib/libnbhd.a"
if [ "$keep_symbols" = 0 ]; then
    # The shared library was stripped by the profile; this also covers a linker that left
    # something behind. --strip-debug (not --strip-all) on the archive keeps the symbols its
    # objects are linked by.
    strip --strip-unneeded "$prefix/lib/$real_name"
    strip --strip-debug "$prefix/lib/libnbhd.a"
fi

cat >"$prefix/lib/cmake/nbhd/nbhdConfig.cmake" <<EOF
# CMake package of nbhd $version, written by scripts/install.sh.
#
#   find_package(nbhd CONFIG REQUIRED)
#   target_link_libraries(app PRIVATE nbhd::nbhd)          # shared library
#   target_link_libraries(app PRIVATE nbhd::nbhd_static)   # static library
#
# Sets nbhd_FOUND, nbhd_VERSION, nbhd_INCLUDE_DIR (holding nbhd.h, nbhd.hpp and nbhd_pcl.hpp,
# the pcl::search backend: link PCL too), nbhd_LIBRARY,
# nbhd_STATIC_LIBRARY.
include(CMakeFindDependencyMacro)
find_dependency(Threads)

get_filename_component(_nbhd_prefix "\${CMAKE_CURRENT_LIST_DIR}/../../.." ABSOLUTE)
set(nbhd_INCLUDE_DIR "\${_nbhd_prefix}/include/nbhd")
set(nbhd_LIBRARY "\${_nbhd_prefix}/lib/libnbhd.so")
set(nbhd_STATIC_LIBRARY "\${_nbhd_prefix}/lib/libnbhd.a")
foreach(_nbhd_file IN ITEMS "\${nbhd_INCLUDE_DIR}/nbhd.h" "\${nbhd_INCLUDE_DIR}/nbhd.hpp"
        "\${nbhd_INCLUDE_DIR}/nbhd_pcl.hpp"
        "\${_nbhd_prefix}/lib/$real_name"
        "\${_nbhd_prefix}/lib/$soname" "\${nbhd_LIBRARY}" "\${nbhd_STATIC_LIBRARY}")
  if(NOT EXISTS "\${_nbhd_file}")
    set(nbhd_FOUND FALSE)
    set(nbhd_NOT_FOUND_MESSAGE "nbhd: \${_nbhd_file} is missing; reinstall with scripts/install.sh")
    return()
  endif()
endforeach()

if(NOT TARGET nbhd::nbhd)
  # lib/$real_name is the library, with the SONAME $soname (lib/$soname links to it);
  # as in CMake's own exported targets, the imported location is the real file and
  # IMPORTED_SONAME names the SONAME. Programs are linked by path, record NEEDED $soname, and
  # get lib/ in their build RPATH.
  add_library(nbhd::nbhd SHARED IMPORTED)
  set_target_properties(nbhd::nbhd PROPERTIES
    IMPORTED_LOCATION "\${_nbhd_prefix}/lib/$real_name"
    IMPORTED_SONAME "$soname"
    INTERFACE_INCLUDE_DIRECTORIES "\${nbhd_INCLUDE_DIR}")
endif()
if(NOT TARGET nbhd::nbhd_static)
  add_library(nbhd::nbhd_static STATIC IMPORTED)
  set_target_properties(nbhd::nbhd_static PROPERTIES
    IMPORTED_LOCATION "\${nbhd_STATIC_LIBRARY}"
    IMPORTED_LINK_INTERFACE_LANGUAGES "C"
    INTERFACE_INCLUDE_DIRECTORIES "\${nbhd_INCLUDE_DIR}"
    INTERFACE_LINK_LIBRARIES "$static_deps_cmake")
endif()
unset(_nbhd_file)
unset(_nbhd_prefix)
EOF

cat >"$prefix/lib/cmake/nbhd/nbhdConfigVersion.cmake" <<EOF
# Version of the nbhd package, written by scripts/install.sh. Compatible with a requested
# version that is not newer and has the same major version (for 0.x: the same minor version,
# as Cargo's semver rules say).
set(PACKAGE_VERSION "$version")
set(PACKAGE_VERSION_COMPATIBLE FALSE)
set(PACKAGE_VERSION_EXACT FALSE)
if(PACKAGE_FIND_VERSION VERSION_EQUAL PACKAGE_VERSION)
  set(PACKAGE_VERSION_EXACT TRUE)
endif()
if(NOT PACKAGE_FIND_VERSION VERSION_GREATER PACKAGE_VERSION)
  if("$v_major" STREQUAL "0")
    if(PACKAGE_FIND_VERSION_MAJOR STREQUAL "0" AND PACKAGE_FIND_VERSION_MINOR STREQUAL "$v_minor")
      set(PACKAGE_VERSION_COMPATIBLE TRUE)
    endif()
  elseif(PACKAGE_FIND_VERSION_MAJOR STREQUAL "$v_major")
    set(PACKAGE_VERSION_COMPATIBLE TRUE)
  endif()
endif()
# A 64-bit library: refuse a 32-bit consumer.
if(DEFINED CMAKE_SIZEOF_VOID_P AND NOT CMAKE_SIZEOF_VOID_P EQUAL 8)
  set(PACKAGE_VERSION "\${PACKAGE_VERSION} (64bit)")
  set(PACKAGE_VERSION_UNSUITABLE TRUE)
endif()
EOF

# -lnbhd finds the link lib/libnbhd.so; the program records the SONAME, $soname.
cat >"$prefix/lib/pkgconfig/nbhd.pc" <<EOF
prefix=\${pcfiledir}/../..
exec_prefix=\${prefix}
libdir=\${exec_prefix}/lib
includedir=\${prefix}/include

Name: nbhd
Description: Exact neighbourhoods in point clouds with k-d trees, and point-set smoothing (C API)
Version: $version
Libs: -L\${libdir} -lnbhd
Libs.private: $static_deps_pc
Cflags: -I\${includedir}/nbhd
EOF

# -lnbhd picks libnbhd.so when both libraries are present, so static linking gets its own file.
cat >"$prefix/lib/pkgconfig/nbhd-static.pc" <<EOF
prefix=\${pcfiledir}/../..
exec_prefix=\${prefix}
libdir=\${exec_prefix}/lib
includedir=\${prefix}/include

Name: nbhd-static
Description: nbhd, linked statically (libnbhd.a and the system libraries it needs)
Version: $version
Libs: \${libdir}/libnbhd.a $static_deps_pc
Cflags: -I\${includedir}/nbhd
EOF

if [ "$keep_symbols" = 0 ]; then what="stripped, no debug information"; else what="with symbols and line tables"; fi
echo "== installed nbhd $version ($profile profile, $what):"
(cd "$prefix" && find include/nbhd/nbhd.h include/nbhd/nbhd.hpp include/nbhd/nbhd_pcl.hpp "lib/$real_name" "lib/$soname" lib/libnbhd.so lib/libnbhd.a \
    lib/cmake/nbhd lib/pkgconfig/nbhd.pc lib/pkgconfig/nbhd-static.pc \( -type f -o -type l \) \
    -printf '%p\n' | sort | while read -r f; do
        if [ -L "$f" ]; then echo "   $f -> $(readlink "$f")"; else echo "   $f ($(stat -c %s "$f") bytes)"; fi
    done)
