# `cpack -G DEB` from the build directory: pidlab_<version>_amd64.deb, one
# package with everything `cmake --install` installs, under /usr.
#
# Depends: the shared libraries the four executables need (what
# dpkg-shlibdeps finds on them, written out so the package does not depend on
# the build machine; Ceres is linked from Debian's static libceres.a, so its
# own libraries are listed, not libceres3). Recommends: what some commands
# run (lcm-logger for `pidlab launch --log`, gnuplot for plots and the report)
# and the -dev packages the installed headers, the CMake package and pidlab.pc
# need. apt installs Recommends by default, so `apt-get install ./pidlab_*.deb`
# gives a machine that can build examples/consumer; --no-install-recommends
# gives the command line alone. One package rather than a pidlab/pidlab-dev
# split: the libraries are static and small, and the headers cost nothing.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME pidlab)
set(CPACK_PACKAGE_VENDOR pidlab)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "PID tuning by Nelder-Mead, run as a distributed LCM plant/controller/disturbance trio")
set(CPACK_PACKAGE_DESCRIPTION
    "pidlab tunes PID gains after the paper's Nelder-Mead stepper-motor study and runs the loop as three LCM processes in lockstep. The package holds the pidlab command, the trio's processes, the static libraries with their headers, a CMake package and pidlab.pc, the LCM message definitions with their C++ and Python code.")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_MAINTAINER "pidlab maintainers <pidlab@localhost>")
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE amd64)
set(CPACK_DEBIAN_PACKAGE_DEPENDS
    "libc6 (>= 2.35), libstdc++6 (>= 12), libgcc-s1 (>= 4.0), liblcm1, libsodium23 (>= 0.6.0), libgoogle-glog0v6 (>= 0.6.0), libcholmod3 (>= 1:4.5.2), libcxsparse3 (>= 1:4.5.2), libspqr2 (>= 1:4.5.2), liblapack3 | liblapack.so.3, libatlas3-base")
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS
    "liblcm-bin, gnuplot-nox | gnuplot, liblcm-dev, libeigen3-dev, libceres-dev, libsodium-dev, libcli11-dev, nlohmann-json3-dev, pkg-config, cmake")
if(PIDLAB_BUILD_PYTHON)
  # The Python module is built for Debian 12's python3 (3.11).
  string(APPEND CPACK_DEBIAN_PACKAGE_RECOMMENDS ", python3 (>= 3.11), python3 (<< 3.12)")
endif()
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "python3-matplotlib, default-jre-headless, liblcm-java")
set(CPACK_DEBIAN_COMPRESSION_TYPE gzip)
set(CPACK_STRIP_FILES ON)
include(CPack)
