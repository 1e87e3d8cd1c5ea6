/* fuzz_inputs.h: fuzz entry points for every parser that reads input from outside the program:
 * the scene and rig INI files and Modbus map files (through their real loaders), `--set` overrides, the API's request
 * line and JSON bodies (router and body checks, no socket), whole API requests with headers (the
 * guard's and the server's reading of a head, api_head.c), the camera calibration file, the
 * replay rails CSV and the sweep CSV a resumed sweep reads. Each takes arbitrary bytes and must
 * neither crash nor leak nor trip a sanitizer; each checks its parser's contract (a refusal has a
 * reason, an acceptance holds only finite, in-range values) and abort()s when it is broken.
 *
 * Built two ways: as libFuzzer targets by the fuzz project (fuzz/CMakeLists.txt, clang, each
 * file then also defines LLVMFuzzerTestOneInput), and always linked into
 * tests/fuzz/test_fuzz_inputs_replay.c, which replays the seed corpus (fuzz/corpus/<target>/)
 * and a fixed stream of mutations in every build, sanitizers included.
 *
 * The targets that need shipped files (the rig's scene) find them under RIBBON_SOURCE_DIR. */
#ifndef RIBBON_FUZZ_INPUTS_H
#define RIBBON_FUZZ_INPUTS_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

int fuzz_scene_ini_one(const uint8_t *data, size_t size);
int fuzz_rig_ini_one(const uint8_t *data, size_t size);
int fuzz_map_ini_one(const uint8_t *data, size_t size);
int fuzz_set_override_one(const uint8_t *data, size_t size);
int fuzz_api_request_one(const uint8_t *data, size_t size);
int fuzz_api_headers_one(const uint8_t *data, size_t size);
int fuzz_calib_file_one(const uint8_t *data, size_t size);
int fuzz_replay_rails_one(const uint8_t *data, size_t size);
int fuzz_sweep_csv_one(const uint8_t *data, size_t size);

/* A harness invariant broke: report it (stderr) and abort, which the fuzzer reports as a crash. */
void fuzz_fail(const char *target, const char *what);

#ifdef __cplusplus
}
#endif

/* Defines LLVMFuzzerTestOneInput as `one` in a libFuzzer build. */
#ifdef RIBBON_LIBFUZZER
#define FUZZ_ENTRY(one)                                                                            \
    int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);                                  \
    int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) { return one(data, size); }
#else
#define FUZZ_ENTRY(one)
#endif

#endif
