# `make deb`: one Debian package of the whole rig, built by CPack from the ordinary install rules
# (cpack -G DEB in the build folder). Installed with `apt install ./hapfluid_<version>_<arch>.deb`,
# it pulls in its dependencies, creates the hapfluid user, reloads udev and systemd, and leaves
# every service disabled; scripts/debian/ holds its maintainer scripts.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME hapfluid)
set(CPACK_PACKAGE_VENDOR hapfluid)
set(CPACK_PACKAGE_CONTACT "hapfluid maintainers <hapfluid@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "real-time haptic fluid stack: 1 kHz loop, SPH simulator, renderer")
set(CPACK_PACKAGE_DESCRIPTION "Lets a person feel a fluid through 6-DoF haptic devices: a hard-real-time 1 kHz \
coupling loop with its safety layer (haptic-rt), an SPH fluid and rigid-body simulator (haptic-sim), a Vulkan \
renderer (haptic-render), a trace logger, fake devices for rigs without hardware, systemd units, udev rules \
and the hapfluid Python tools (launcher, CAN monitor, plots and latency reports).")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
# The units, the udev rules and sysusers.d name /usr and /etc paths: install there, through DESTDIR.
# (whatever prefix the build folder was configured with for `make install`).
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_INSTALL_PREFIX /usr)
set(CPACK_SET_DESTDIR ON)
set(CPACK_STRIP_FILES ON)
set(CPACK_PACKAGE_DIRECTORY ${CMAKE_BINARY_DIR}/deb)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
# Shared libraries from dpkg-shlibdeps; what the binaries load at run time (Vulkan through volk)
# or run (systemd-sysusers, udevadm), and the Python package's imports, by name.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS
    "libvulkan1, systemd, udev, python3 (>= 3.11), python3-numpy, python3-matplotlib, python3-can, python3-tomli-w, python3-aiohttp")
# Lavapipe when the rig has no GPU driver of its own; cyclictest for the launcher's latency reference.
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "mesa-vulkan-drivers, rt-tests")
set(_debian ${CMAKE_SOURCE_DIR}/scripts/debian)
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA ${_debian}/postinst ${_debian}/prerm ${_debian}/postrm ${_debian}/conffiles)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
include(CPack)
