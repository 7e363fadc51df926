# Every dependency comes from Debian 12 packages (deploy/setup.sh installs them).

find_package(Threads REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(Boost 1.74 REQUIRED COMPONENTS system filesystem)
find_package(OpenSSL REQUIRED)
find_package(SQLite3 REQUIRED)
# libpqxx (Debian libpqxx-dev, 6.4) has no CMake package on Debian 12: pkg-config.
find_package(PkgConfig REQUIRED)
pkg_check_modules(PQXX REQUIRED IMPORTED_TARGET libpqxx)
# zstd and lz4 (MCAP chunk compression) have no CMake config on Debian 12: pkg-config.
pkg_check_modules(ZSTD REQUIRED IMPORTED_TARGET libzstd)
pkg_check_modules(LZ4 REQUIRED IMPORTED_TARGET liblz4)
# bzip2: ROS1 bag chunks (worker/io/bag/ros1_chunk.cc).
find_package(BZip2 REQUIRED)
find_package(LibArchive REQUIRED)
# PROJ (libproj-dev, 9.1): WGS 84 <-> local ENU; pkg-config (its CMake package is named by version).
pkg_check_modules(PROJ REQUIRED IMPORTED_TARGET proj)
find_package(CLI11 REQUIRED)
find_package(spdlog REQUIRED)
find_package(yaml-cpp REQUIRED)
find_package(draco REQUIRED)
find_package(Ceres REQUIRED)
# SuiteSparse_config (libsuitesparse-dev, Ceres's own dependency): core/suitesparse_memory.h.
find_path(SUITESPARSE_CONFIG_INCLUDE_DIR SuiteSparse_config.h PATH_SUFFIXES suitesparse REQUIRED)
find_library(SUITESPARSE_CONFIG_LIBRARY suitesparseconfig REQUIRED)
find_package(OpenCV REQUIRED COMPONENTS core imgproc imgcodecs features2d calib3d)
find_package(CGAL REQUIRED)
find_package(PCL 1.12 REQUIRED COMPONENTS common io filters kdtree search registration)
if(KEEL_BUILD_TESTS)
  find_package(GTest REQUIRED)
  find_package(benchmark REQUIRED)
endif()

# Debian's yaml-cpp exports a plain `yaml-cpp` target.
if(NOT TARGET yaml-cpp::yaml-cpp)
  add_library(yaml-cpp::yaml-cpp INTERFACE IMPORTED)
  set_target_properties(yaml-cpp::yaml-cpp PROPERTIES INTERFACE_LINK_LIBRARIES yaml-cpp)
endif()

add_library(keel_suitesparseconfig INTERFACE)
target_include_directories(keel_suitesparseconfig SYSTEM INTERFACE ${SUITESPARSE_CONFIG_INCLUDE_DIR})
target_link_libraries(keel_suitesparseconfig INTERFACE ${SUITESPARSE_CONFIG_LIBRARY})

# PCL as one interface target (its variables are not target-based on Debian 12), without its
# I/O: pcl_io brings VTK and ~70 shared libraries that every program start would load (Keel
# reads and writes PCD itself). Tests that check Keel's files with PCL's reader link
# keel_pcl_io.
set(KEEL_PCL_LIBRARIES ${PCL_LIBRARIES})
list(FILTER KEEL_PCL_LIBRARIES EXCLUDE REGEX "pcl_io|^VTK::|vtk")
add_library(keel_pcl INTERFACE)
target_include_directories(keel_pcl SYSTEM INTERFACE ${PCL_INCLUDE_DIRS})
target_link_libraries(keel_pcl INTERFACE ${KEEL_PCL_LIBRARIES})
target_compile_definitions(keel_pcl INTERFACE ${PCL_DEFINITIONS})
add_library(keel_pcl_io INTERFACE)
target_link_libraries(keel_pcl_io INTERFACE keel_pcl ${PCL_LIBRARIES})

# OpenCV without imgcodecs for the programs (its Debian build pulls GDAL and ~140 shared
# libraries; Keel decodes PNG and JPEG with libpng and libjpeg): keel_opencv. Tests encode
# reference images with imgcodecs: keel_opencv_imgcodecs.
find_package(PNG REQUIRED)
find_package(JPEG REQUIRED)
add_library(keel_opencv INTERFACE)
target_include_directories(keel_opencv SYSTEM INTERFACE ${OpenCV_INCLUDE_DIRS})
target_link_libraries(keel_opencv INTERFACE opencv_core opencv_imgproc opencv_features2d opencv_calib3d)
add_library(keel_opencv_imgcodecs INTERFACE)
target_link_libraries(keel_opencv_imgcodecs INTERFACE keel_opencv opencv_imgcodecs)

# ROS1's own C++ bag library and message types, for keel-sim and tests only: keel-sim writes
# its ROS1 bags with it, an independent writer for Keel's own reader (worker/io/bag/ros1_bag.h),
# and tests serialise messages with roscpp. keel, keel-worker and keel-server do not link it
# (it pulls class_loader, roslib, rospack and libpython3.11). `pkg-config rosbag_storage` is
# broken on Debian 12, so the include dirs and libraries are listed by hand.
add_library(keel_rosbag INTERFACE)
target_include_directories(keel_rosbag SYSTEM INTERFACE
  /usr/include/pluginlib /usr/include/class_loader /usr/include/rcpputils
  /usr/include/rcutils /usr/include/ament_index_cpp)
target_link_libraries(keel_rosbag INTERFACE
  rosbag_storage roscpp_serialization rostime cpp_common console_bridge
  Boost::filesystem boost_regex roslz4 bz2)
