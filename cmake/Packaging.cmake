# Debian packages (`cpack -G DEB` in a build tree, docs/deploy.md), one per install component:
#   arbiter          runtime: the engine's core and tools libraries, the CLI, bash completion, the
#                    config schema
#   arbiter-plugins  plugins: the plugins that were built (soccer, dds) and the demo configs
#   arbiter-dev      dev: headers, the CMake package config and arbiter_add_plugin()
#   python3-arbiter  python: the Python module (where it was built, ARBITER_PYTHON)
# Library dependencies come from dpkg-shlibdeps (Debian's own package names: libyaml-cpp0.7,
# libddsc0debian, ...); the packages depend on each other at this exact version.
set(CPACK_PACKAGE_NAME arbiter)
set(CPACK_PACKAGE_VENDOR "Arbiter")
set(CPACK_PACKAGE_CONTACT "Arbiter maintainers <arbiter@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_VERSION "${PROJECT_VERSION}")
set(CPACK_COMPONENTS_ALL runtime plugins dev)
if(ARBITER_PYTHON)
  list(APPEND CPACK_COMPONENTS_ALL python)
endif()
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_RELEASE 1)
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# The plugins link the core library of the arbiter package, which dpkg-shlibdeps finds in the
# build tree; the dependency on it is declared below, at this exact version.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS_PRIVATE_DIRS "${PROJECT_BINARY_DIR}/engine")
set(CPACK_DEBIAN_PACKAGE_GENERATE_SHLIBS ON)
set(CPACK_DEBIAN_ENABLE_COMPONENT_DEPENDS ON)
set(version "${PROJECT_VERSION}-${CPACK_DEBIAN_PACKAGE_RELEASE}")

set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME arbiter)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SECTION misc)
set(CPACK_COMPONENT_RUNTIME_DESCRIPTION
    "Data-driven behaviour engine for robots: the engine's libraries and the arbiter command
 Behaviour layers, inhibitions and state controllers declared in YAML or JSON configs,
 validated with file:line:column diagnostics and bound to C++ classes. The core library runs
 them; the tools library (dumps, lints, explain, the schema, scenario tests) serves the command.")

set(CPACK_DEBIAN_PLUGINS_PACKAGE_NAME arbiter-plugins)
set(CPACK_DEBIAN_PLUGINS_PACKAGE_DEPENDS "arbiter (= ${version})")
set(CPACK_COMPONENT_PLUGINS_DESCRIPTION
    "Plugins for Arbiter: the soccer demo and the DDS bridge
 The soccer plugin and its demo configs (/usr/share/arbiter/configs), and, where it was built,
 the DDS bridge (Eclipse Cyclone DDS) that talks to ROS 2 nodes.")

set(CPACK_DEBIAN_DEV_PACKAGE_NAME arbiter-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
# find_package(arbiter) finds fmt (the engine's headers use it); plugins are built with CMake.
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS "arbiter (= ${version}), libfmt-dev, cmake (>= 3.25)")
set(CPACK_DEBIAN_DEV_PACKAGE_RECOMMENDS "g++")
set(CPACK_COMPONENT_DEV_DESCRIPTION
    "Development files for Arbiter plugins
 The engine's headers, the CMake package config (find_package(arbiter): the targets
 arbiter::core and arbiter::tools) and arbiter_add_plugin(), to build plugins against the
 installed core library.")

# The extension module is built for one Python minor version (its file name says which:
# _arbiter.cpython-311-...so) and links no libpython, so dpkg-shlibdeps cannot see that it needs
# that Python: it is declared. pandas is what to_dataframe() needs.
set(CPACK_DEBIAN_PYTHON_PACKAGE_NAME python3-arbiter)
set(CPACK_DEBIAN_PYTHON_PACKAGE_SECTION python)
math(EXPR next_minor_number "${Python_VERSION_MINOR} + 1")
set(CPACK_DEBIAN_PYTHON_PACKAGE_DEPENDS
    "arbiter (= ${version}), python3 (>= ${Python_VERSION_MAJOR}.${Python_VERSION_MINOR}), python3 (<< ${Python_VERSION_MAJOR}.${next_minor_number})")
set(CPACK_DEBIAN_PYTHON_PACKAGE_RECOMMENDS "python3-pandas, python3-pytest")
set(CPACK_COMPONENT_PYTHON_DESCRIPTION
    "Python module for Arbiter
 import arbiter: load and validate configs, step a program, read traces and recordings (as
 pandas DataFrames), run scenario tests from pytest, and write behaviour and state classes in
 Python.")

include(CPack)
