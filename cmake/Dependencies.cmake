# All dependencies come from Debian 12 packages (installed by tools/setup.sh).
find_package(Threads REQUIRED)
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(yaml-cpp REQUIRED)
find_package(CLI11 REQUIRED)
find_package(fmt REQUIRED)
find_package(spdlog REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
find_package(OpenSSL REQUIRED)
find_package(muparser REQUIRED)
find_package(HDF5 REQUIRED COMPONENTS C CXX)
find_package(pugixml REQUIRED)
find_package(Torch REQUIRED)
# libdeflate: compresses the HDF5 outputs' chunks (zlib format, what HDF5's deflate filter reads).
find_package(PkgConfig REQUIRED)
pkg_check_modules(LIBDEFLATE REQUIRED IMPORTED_TARGET libdeflate)

# libsumo ships headers and libsumocpp.so in Debian's `sumo` package, but no
# CMake config: wrap it in an imported target.
find_path(LIBSUMO_INCLUDE_DIR libsumo/libsumo.h REQUIRED)
find_library(LIBSUMO_LIBRARY sumocpp REQUIRED)
add_library(libsumo::libsumo UNKNOWN IMPORTED)
set_target_properties(libsumo::libsumo PROPERTIES
  IMPORTED_LOCATION "${LIBSUMO_LIBRARY}"
  INTERFACE_SYSTEM_INCLUDE_DIRECTORIES "${LIBSUMO_INCLUDE_DIR}"
  INTERFACE_INCLUDE_DIRECTORIES "${LIBSUMO_INCLUDE_DIR}")

# HDF5's C++ API (H5Cpp.h lives in hdf5/serial on Debian).
add_library(vsd_hdf5 INTERFACE)
target_include_directories(vsd_hdf5 SYSTEM INTERFACE ${HDF5_INCLUDE_DIRS})
target_link_libraries(vsd_hdf5 INTERFACE ${HDF5_CXX_LIBRARIES} ${HDF5_LIBRARIES})
target_compile_definitions(vsd_hdf5 INTERFACE ${HDF5_DEFINITIONS})

# libtorch: only the `model` and `baseline` modules link it, privately.
add_library(vsd_torch INTERFACE)
target_include_directories(vsd_torch SYSTEM INTERFACE ${TORCH_INCLUDE_DIRS})
target_link_libraries(vsd_torch INTERFACE ${TORCH_LIBRARIES})

# Executables used at run time and by tests.
find_program(VSD_NETCONVERT netconvert REQUIRED)
find_program(VSD_SYSTEM_PYTHON python3 PATHS /usr/bin NO_DEFAULT_PATH)

# MPI is optional: with it, `mpirun -n N vsd-sumo run|export` splits the work over
# ranks; without it the tool runs as one process and refuses to be started by mpirun.
option(VSD_WITH_MPI "Use MPI when it is installed (Debian: libopenmpi-dev openmpi-bin)" ON)
if(VSD_WITH_MPI)
  find_package(MPI COMPONENTS C)
endif()
if(MPI_C_FOUND)
  message(STATUS "MPI: version ${MPI_C_VERSION} (mpiexec: ${MPIEXEC_EXECUTABLE})")
else()
  message(STATUS "MPI: not found, building without it")
endif()
