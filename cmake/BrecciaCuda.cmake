# Decide whether the CUDA backend is built. nvcc is on every machine we target, a GPU is not:
# the backend always builds where nvcc exists; whether a device is present is a run-time question.
set(BRECCIA_HAVE_CUDA OFF)
if(BRECCIA_CUDA STREQUAL "ON" OR BRECCIA_CUDA STREQUAL "AUTO")
  if(NOT CMAKE_CUDA_COMPILER AND EXISTS /usr/local/cuda/bin/nvcc)
    set(CMAKE_CUDA_COMPILER /usr/local/cuda/bin/nvcc)
  endif()
  include(CheckLanguage)
  check_language(CUDA)
  if(CMAKE_CUDA_COMPILER)
    if(NOT DEFINED CMAKE_CUDA_ARCHITECTURES)
      # Hopper (H100/H200) is the target device; one architecture keeps the build short.
      # Set before enable_language, which would otherwise pick nvcc's default.
      set(CMAKE_CUDA_ARCHITECTURES 90)
    endif()
    # CMake 3.25 knows nvcc's dialects only up to C++17; tell it the C++20 flag.
    set(CMAKE_CUDA20_STANDARD_COMPILE_OPTION "-std=c++20")
    set(CMAKE_CUDA20_EXTENSION_COMPILE_OPTION "-std=c++20")
    enable_language(CUDA)
    set(CMAKE_CUDA_STANDARD 20)
    set(CMAKE_CUDA_STANDARD_REQUIRED ON)
    find_package(CUDAToolkit REQUIRED)
    set(BRECCIA_HAVE_CUDA ON)
  elseif(BRECCIA_CUDA STREQUAL "ON")
    message(FATAL_ERROR "BRECCIA_CUDA=ON but no CUDA compiler (nvcc) was found")
  endif()
endif()
message(STATUS "Breccia CUDA backend: ${BRECCIA_HAVE_CUDA}")
