/* uhid -> hidraw -> hidapi on the real kernel, in one process.
 *
 * A userspace HID device (UHID_CREATE2) with a vendor-defined 64-byte report descriptor, the
 * shape the project's HID devices use, must appear as /dev/hidrawN, be enumerated by hidapi's
 * hidraw backend by VID:PID, stream input reports that hidapi reads intact and in order, receive
 * the output reports hidapi writes (with hidraw's leading report-ID byte 0x00 stripped the way a
 * device without report IDs must) and answer a feature-report request. When the device is
 * destroyed the hidraw node must go away, which is how a host driver notices an unplug.
 *
 *   hil-uhid-probe [VID PID]      (hex, default 1209 0001: the pid.codes test VID:PID)
 */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <hidapi/hidapi.h>
#include <linux/uhid.h>
#include <poll.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#define REPORT_BYTES 64
#define N_INPUT 200
#define N_OUTPUT 20

static const uint8_t report_descriptor[] = {
    0x06, 0x00, 0xFF, /* Usage Page (Vendor 0xFF00) */
    0x09, 0x01,       /* Usage (1) */
    0xA1, 0x01,       /* Collection (Application) */
    0x15, 0x00, 0x26, 0xFF, 0x00, /* Logical Minimum 0, Maximum 255 */
    0x75, 0x08, 0x95, REPORT_BYTES, /* Report Size 8, Report Count 64 */
    0x09, 0x02, 0x81, 0x02, /* Usage (2), Input (Data,Var,Abs) */
    0x09, 0x03, 0x91, 0x02, /* Usage (3), Output (Data,Var,Abs) */
    0x09, 0x04, 0xB1, 0x02, /* Usage (4), Feature (Data,Var,Abs) */
    0xC0,             /* End Collection */
};

static int uhid_fd = -1;
static atomic_int opened, stop, outputs_ok, outputs_bad, feature_requests;
static unsigned vid = 0x1209, pid = 0x0001;

#define FAIL(...) do { printf("FAIL: " __VA_ARGS__); printf("\n"); exit(1); } while (0)

static void input_pattern(uint8_t *r, uint32_t seq) {
    memcpy(r, &seq, 4);
    for (int i = 4; i < REPORT_BYTES; i++) r[i] = (uint8_t)(seq * 31u + (unsigned)i);
}
static void output_pattern(uint8_t *r, uint32_t n) {
    for (int i = 0; i < REPORT_BYTES; i++) r[i] = (uint8_t)(0xC3u ^ (n * 7u + (unsigned)i));
}

static void uhid_write(const struct uhid_event *ev) {
    if (write(uhid_fd, ev, sizeof *ev) != (ssize_t)sizeof *ev) FAIL("write /dev/uhid: %s", strerror(errno));
}

/* The device side: answers the kernel's uhid events and streams input reports every ~2 ms once a
 * reader has the hidraw node open (hidraw drops reports sent the instant UHID_OPEN arrives). */
static void *device_thread(void *arg) {
    (void)arg;
    uint32_t seq = 0, next_output = 0;
    while (!atomic_load(&stop)) {
        struct pollfd p = {.fd = uhid_fd, .events = POLLIN};
        int r = poll(&p, 1, 2);
        if (r > 0) {
            struct uhid_event ev;
            ssize_t n = read(uhid_fd, &ev, sizeof ev);
            if (n <= 0) continue;
            switch (ev.type) {
            case UHID_OPEN: atomic_store(&opened, 1); break;
            case UHID_CLOSE: atomic_store(&opened, 0); break;
            case UHID_OUTPUT: {
                const uint8_t *d = ev.u.output.data;
                size_t len = ev.u.output.size;
                if (len == REPORT_BYTES + 1 && d[0] == 0) { d++; len--; } /* hidraw's report-ID 0 */
                uint8_t want[REPORT_BYTES];
                output_pattern(want, next_output);
                if (len == REPORT_BYTES && memcmp(d, want, REPORT_BYTES) == 0) {
                    atomic_fetch_add(&outputs_ok, 1);
                } else {
                    printf("output report %u: %zu bytes, first 0x%02x: not what was written\n",
                           next_output, len, len ? d[0] : 0);
                    atomic_fetch_add(&outputs_bad, 1);
                }
                next_output++;
                break;
            }
            case UHID_GET_REPORT: {
                struct uhid_event rep = {.type = UHID_GET_REPORT_REPLY};
                rep.u.get_report_reply.id = ev.u.get_report.id;
                rep.u.get_report_reply.err = 0;
                rep.u.get_report_reply.size = REPORT_BYTES;
                for (int i = 0; i < REPORT_BYTES; i++) rep.u.get_report_reply.data[i] = (uint8_t)(0xF0 ^ i);
                uhid_write(&rep);
                atomic_fetch_add(&feature_requests, 1);
                break;
            }
            default: break;
            }
        }
        if (atomic_load(&opened)) {
            struct uhid_event in = {.type = UHID_INPUT2};
            in.u.input2.size = REPORT_BYTES;
            input_pattern(in.u.input2.data, seq++);
            uhid_write(&in);
        }
    }
    return NULL;
}

int main(int argc, char **argv) {
    setvbuf(stdout, NULL, _IOLBF, 0);
    if (argc == 3) { vid = (unsigned)strtoul(argv[1], NULL, 16); pid = (unsigned)strtoul(argv[2], NULL, 16); }
    uhid_fd = open("/dev/uhid", O_RDWR | O_CLOEXEC);
    if (uhid_fd < 0) FAIL("open /dev/uhid: %s (is the uhid module loaded?)", strerror(errno));
    struct uhid_event create = {.type = UHID_CREATE2};
    snprintf((char *)create.u.create2.name, sizeof create.u.create2.name, "hapfluid HIL uhid probe");
    snprintf((char *)create.u.create2.uniq, sizeof create.u.create2.uniq, "HIL-0001");
    create.u.create2.rd_size = sizeof report_descriptor;
    create.u.create2.bus = 0x03; /* BUS_USB */
    create.u.create2.vendor = vid;
    create.u.create2.product = pid;
    memcpy(create.u.create2.rd_data, report_descriptor, sizeof report_descriptor);
    uhid_write(&create);
    pthread_t th;
    pthread_create(&th, NULL, device_thread, NULL);

    if (hid_init() != 0) FAIL("hid_init");
    char path[256] = "";
    for (int tries = 0; tries < 400 && !path[0]; tries++) {
        struct hid_device_info *list = hid_enumerate((unsigned short)vid, (unsigned short)pid);
        for (struct hid_device_info *d = list; d; d = d->next) {
            printf("hidapi enumerates %04x:%04x at %s, product \"%ls\", usage page 0x%04x\n",
                   d->vendor_id, d->product_id, d->path, d->product_string ? d->product_string : L"",
                   d->usage_page);
            snprintf(path, sizeof path, "%s", d->path);
        }
        hid_free_enumeration(list);
        if (!path[0]) usleep(25000);
    }
    if (!path[0]) FAIL("hidapi never enumerated %04x:%04x", vid, pid);
    if (strncmp(path, "/dev/hidraw", 11) != 0) FAIL("device path %s is not a hidraw node", path);
    hid_device *h = hid_open_path(path);
    if (!h) FAIL("hid_open_path(%s): %ls", path, hid_error(NULL));

    /* Input reports: in order, no corruption. The first few may be lost to the open race. */
    uint8_t buf[REPORT_BYTES + 1];
    int64_t last = -1;
    for (int i = 0; i < N_INPUT; i++) {
        int n = hid_read_timeout(h, buf, sizeof buf, 5000);
        if (n != REPORT_BYTES) FAIL("input report %d: hid_read returned %d (%ls)", i, n, hid_error(h));
        uint32_t seq;
        memcpy(&seq, buf, 4);
        uint8_t want[REPORT_BYTES];
        input_pattern(want, seq);
        if (memcmp(buf, want, REPORT_BYTES) != 0) FAIL("input report seq %u corrupted", seq);
        if ((int64_t)seq <= last) FAIL("input report seq %u after %lld: out of order", seq, (long long)last);
        last = seq;
    }
    printf("read %d input reports of %d bytes, in order (last seq %lld)\n", N_INPUT, REPORT_BYTES, (long long)last);

    /* Output reports: hidapi's first byte is the report ID (0 = none). */
    for (uint32_t i = 0; i < N_OUTPUT; i++) {
        buf[0] = 0;
        output_pattern(buf + 1, i);
        int n = hid_write(h, buf, sizeof buf);
        if (n < 0) FAIL("hid_write %u: %ls", i, hid_error(h));
    }
    for (int t = 0; t < 500 && atomic_load(&outputs_ok) + atomic_load(&outputs_bad) < N_OUTPUT; t++) usleep(10000);
    if (atomic_load(&outputs_ok) != N_OUTPUT)
        FAIL("device received %d intact output reports of %d written (%d bad)", atomic_load(&outputs_ok),
             N_OUTPUT, atomic_load(&outputs_bad));
    printf("device received %d output reports intact\n", N_OUTPUT);

    /* Feature report: GET_REPORT goes to the device and its reply comes back. */
    memset(buf, 0, sizeof buf);
    int n = hid_get_feature_report(h, buf, sizeof buf);
    if (n < REPORT_BYTES) FAIL("hid_get_feature_report returned %d: %ls", n, hid_error(h));
    const uint8_t *f = buf + (n == REPORT_BYTES + 1 ? 1 : 0);
    for (int i = 0; i < REPORT_BYTES; i++)
        if (f[i] != (uint8_t)(0xF0 ^ i)) FAIL("feature report byte %d is 0x%02x", i, f[i]);
    printf("feature report (%d bytes) answered by the device\n", n);
    hid_close(h);

    /* Unplug: destroying the uhid device removes the hidraw node. */
    atomic_store(&stop, 1);
    pthread_join(th, NULL);
    struct uhid_event destroy = {.type = UHID_DESTROY};
    uhid_write(&destroy);
    struct stat st;
    int gone = 0;
    for (int t = 0; t < 400 && !gone; t++) { gone = stat(path, &st) != 0; if (!gone) usleep(25000); }
    if (!gone) FAIL("%s still exists after UHID_DESTROY", path);
    struct hid_device_info *left = hid_enumerate((unsigned short)vid, (unsigned short)pid);
    if (left) FAIL("hidapi still enumerates %04x:%04x after UHID_DESTROY", vid, pid);
    hid_exit();
    printf("PASS: uhid %04x:%04x -> %s -> hidapi: %d input, %d output, 1 feature report; node removed on destroy\n",
           vid, pid, path, N_INPUT, N_OUTPUT);
    return 0;
}
