/* fuzz_calib_file.c: fuzz target for the camera calibration file (vision/calib.cpp's
 * vis_calib_load, the real loader on a real file: the input is written to an anonymous memory
 * file and loaded through /proc/self/fd). An accepted calibration passes vis_calib_check; a
 * refusal says why. */
#define _GNU_SOURCE
#include <stdio.h>
#include <sys/mman.h>
#include <unistd.h>

#include "fuzz_inputs.h"
#include "vision.h"

int fuzz_calib_file_one(const uint8_t *data, size_t size)
{
    int fd = memfd_create("fuzz-calib", MFD_CLOEXEC);
    if (fd < 0) return 0;
    size_t done = 0;
    while (done < size) {
        ssize_t w = write(fd, data + done, size - done);
        if (w <= 0) break;
        done += (size_t)w;
    }
    char path[64];
    snprintf(path, sizeof path, "/proc/self/fd/%d", fd);
    vis_calib c;
    vis_error err;
    err.message[0] = '\0';
    if (done == size) {
        if (vis_calib_load(&c, path, &err) == VIS_OK) {
            vis_error e2;
            if (vis_calib_check(&c, &e2) != VIS_OK) fuzz_fail("calib_file", "an accepted calibration fails its check");
        } else if (err.message[0] == '\0') {
            fuzz_fail("calib_file", "a refusal without a reason");
        }
    }
    close(fd);
    return 0;
}

FUZZ_ENTRY(fuzz_calib_file_one)
