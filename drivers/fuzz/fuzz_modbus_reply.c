/* fuzz_modbus_reply.c: fuzz target for Modbus reply handling: the input is served as the
 * drive's answer to a "read 8 holding registers" request over a socketpair, so libmodbus's reply
 * checks (transaction id, function, byte count, exception) run on it exactly as in the driver;
 * a reply that gets through is decoded with both word orders and turned into a rail state with
 * both presets' status bits. The first two input bytes are replaced by the transaction id
 * libmodbus expects, so mutations get past that first check. */
#include <errno.h>
#include <modbus.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "fuzz.h"
#include "rail_modbus.h"

int fuzz_modbus_reply_one(const uint8_t *data, size_t size)
{
    if (size > 300)
        size = 300;
    int sv[2];
    if (socketpair(AF_UNIX, SOCK_STREAM, 0, sv) != 0)
        return 0;
    modbus_t *ctx = modbus_new_tcp("127.0.0.1", 1502);
    if (!ctx) {
        close(sv[0]);
        close(sv[1]);
        return 0;
    }
    modbus_set_socket(ctx, sv[0]);
    modbus_set_error_recovery(ctx, MODBUS_ERROR_RECOVERY_NONE);
    modbus_set_slave(ctx, 1);
    uint16_t regs[8];
    /* First request: nobody answers (short timeout); it tells us libmodbus's transaction id. */
    modbus_set_response_timeout(ctx, 0, 200);
    modbus_read_registers(ctx, 0, 8, regs);
    modbus_set_response_timeout(ctx, 0, 2000);
    modbus_set_byte_timeout(ctx, 0, 2000);
    uint8_t req[32];
    ssize_t n = recv(sv[1], req, sizeof req, MSG_DONTWAIT);
    uint8_t buf[300];
    memcpy(buf, data, size);
    if (n >= 2 && size >= 2) {
        unsigned tid = (((unsigned)req[0] << 8) | req[1]) + 1u;
        buf[0] = (uint8_t)(tid >> 8);
        buf[1] = (uint8_t)tid;
    }
    if (size > 0 && send(sv[1], buf, size, MSG_DONTWAIT) < 0)
        size = 0;
    int rc = modbus_read_registers(ctx, 0, 8, regs);
    if (rc == 8) {
        rail_modbus_map maps[2];
        rail_modbus_preset("ribbon-sim", &maps[0]);
        rail_modbus_preset("oriental-az", &maps[1]);
        for (int m = 0; m < 2; m++) {
            for (int o = 0; o < 2; o++) {
                long pos = rail_mb_get32(regs + 0, (rail_mb_word_order)o);
                long st = rail_mb_get32(regs + 2, (rail_mb_word_order)o);
                char msg[160];
                rail_state s = rail_mb_state_of(&maps[m], (unsigned long)st, (long)regs[4], regs[5] & 1, msg,
                                                sizeof msg);
                if ((int)s < 0 || s >= RAIL_STATE_COUNT || (pos > 2147483647L || pos < -2147483648L))
                    abort();
            }
        }
    } else if (rc != -1) {
        abort(); /* libmodbus returns the count or -1, nothing else */
    }
    modbus_set_socket(ctx, -1);
    modbus_free(ctx);
    close(sv[0]);
    close(sv[1]);
    return 0;
}

#ifdef RIBBON_LIBFUZZER
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_modbus_reply_one(data, size);
}
#endif
