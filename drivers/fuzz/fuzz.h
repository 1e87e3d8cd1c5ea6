/* fuzz.h: the drivers' fuzz entry points. Each takes arbitrary bytes and must neither crash nor
 * leak nor trip a sanitizer, whatever they are. Built two ways: as libFuzzer targets (clang,
 * -DRIBBON_FUZZ=ON: each file then also defines LLVMFuzzerTestOneInput) and, always, linked into
 * tests/drivers/test_fuzz_replay.c, which replays seeds and a fixed stream of mutations so CI
 * runs them briefly in every build, sanitizers included. */
#ifndef RIBBON_DRIVERS_FUZZ_H
#define RIBBON_DRIVERS_FUZZ_H

#include <stddef.h>
#include <stdint.h>

int fuzz_grbl_status_one(const uint8_t *data, size_t size);
int fuzz_modbus_reply_one(const uint8_t *data, size_t size);

#endif
