/* FunctionFS gadget on dummy_hcd <-> libusb on the real kernel.
 *
 *   hil-usb-ffs-probe device FFS_MOUNT
 *       The gadget's function: writes FS+HS descriptors (one interface, bulk IN + bulk OUT) and
 *       strings to ep0, then echoes every OUT packet back on IN with its bytes complemented,
 *       riding out unbind/rebind (endpoint I/O fails while the UDC is unbound). Runs until killed.
 *   hil-usb-ffs-probe host VID PID UDC_FILE UDC_NAME
 *       The host: opens VID:PID with libusb, finds the bulk endpoints from the descriptors,
 *       checks bulk round trips; unbinds the UDC (a cable pulled) and requires libusb to report
 *       the device gone; rebinds it and requires the device to be found and working again.
 */
#define _GNU_SOURCE
#include <endian.h>
#include <errno.h>
#include <fcntl.h>
#include <libusb-1.0/libusb.h>
#include <linux/usb/functionfs.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define FAIL(...) do { printf("FAIL: " __VA_ARGS__); printf("\n"); exit(1); } while (0)

/* ---- device side ---------------------------------------------------------------------------- */

/* FunctionFS wants little-endian descriptors; glibc's htole32 is not a constant expression, and
 * this probe only ever runs on x86-64. */
_Static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "little-endian host assumed");
#define LE16(x) ((uint16_t)(x))
#define LE32(x) ((uint32_t)(x))

struct ep_descs {
    struct usb_interface_descriptor intf;
    struct usb_endpoint_descriptor_no_audio in, out;
} __attribute__((packed));

#define EP_DESCS(mps) { \
    .intf = {.bLength = sizeof(struct usb_interface_descriptor), .bDescriptorType = USB_DT_INTERFACE, \
             .bNumEndpoints = 2, .bInterfaceClass = USB_CLASS_VENDOR_SPEC, .iInterface = 1}, \
    .in = {.bLength = USB_DT_ENDPOINT_SIZE, .bDescriptorType = USB_DT_ENDPOINT, \
           .bEndpointAddress = 1 | USB_DIR_IN, .bmAttributes = USB_ENDPOINT_XFER_BULK, .wMaxPacketSize = LE16(mps)}, \
    .out = {.bLength = USB_DT_ENDPOINT_SIZE, .bDescriptorType = USB_DT_ENDPOINT, \
            .bEndpointAddress = 2 | USB_DIR_OUT, .bmAttributes = USB_ENDPOINT_XFER_BULK, .wMaxPacketSize = LE16(mps)} }

static const struct {
    struct usb_functionfs_descs_head_v2 header;
    __le32 fs_count, hs_count;
    struct ep_descs fs, hs;
} __attribute__((packed)) descriptors = {
    .header = {.magic = LE32(FUNCTIONFS_DESCRIPTORS_MAGIC_V2),
               .length = LE32(sizeof descriptors),
               .flags = LE32(FUNCTIONFS_HAS_FS_DESC | FUNCTIONFS_HAS_HS_DESC)},
    .fs_count = LE32(3), .hs_count = LE32(3),
    .fs = EP_DESCS(64), .hs = EP_DESCS(512),
};

#define STR_INTERFACE "hapfluid HIL bulk probe"
static const struct {
    struct usb_functionfs_strings_head header;
    struct { __le16 code; char str1[sizeof STR_INTERFACE]; } __attribute__((packed)) lang0;
} __attribute__((packed)) strings = {
    .header = {.magic = LE32(FUNCTIONFS_STRINGS_MAGIC), .length = LE32(sizeof strings),
               .str_count = LE32(1), .lang_count = LE32(1)},
    .lang0 = {LE16(0x0409), STR_INTERFACE},
};

static const char *event_names[] = {"BIND", "UNBIND", "ENABLE", "DISABLE", "SETUP", "SUSPEND", "RESUME"};

static void *ep0_thread(void *arg) {
    int ep0 = *(int *)arg;
    struct usb_functionfs_event ev;
    for (;;) {
        ssize_t n = read(ep0, &ev, sizeof ev);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) { printf("device: ep0 read ended: %s\n", strerror(errno)); return NULL; }
        printf("device: ep0 event %s\n", ev.type < 7 ? event_names[ev.type] : "?");
        if (ev.type == FUNCTIONFS_SETUP) {
            /* No class/vendor control requests here: stall them (read/write of 0 bytes). */
            if (ev.u.setup.bRequestType & USB_DIR_IN) { if (write(ep0, NULL, 0) < 0) {} }
            else { if (read(ep0, NULL, 0) < 0) {} }
        }
    }
}

static int run_device(const char *dir) {
    char p[512];
    snprintf(p, sizeof p, "%s/ep0", dir);
    int ep0 = open(p, O_RDWR);
    if (ep0 < 0) FAIL("open %s: %s", p, strerror(errno));
    if (write(ep0, &descriptors, sizeof descriptors) != (ssize_t)sizeof descriptors) FAIL("write descriptors: %s", strerror(errno));
    if (write(ep0, &strings, sizeof strings) != (ssize_t)sizeof strings) FAIL("write strings: %s", strerror(errno));
    pthread_t th;
    pthread_create(&th, NULL, ep0_thread, &ep0);
    snprintf(p, sizeof p, "%s/ep1", dir);
    int ep_in = open(p, O_RDWR);
    snprintf(p, sizeof p, "%s/ep2", dir);
    int ep_out = open(p, O_RDWR);
    if (ep_in < 0 || ep_out < 0) FAIL("open endpoint files in %s: %s", dir, strerror(errno));
    printf("device: descriptors written, endpoints open\n");
    uint8_t buf[4096];
    unsigned long echoed = 0;
    for (;;) {
        ssize_t n = read(ep_out, buf, sizeof buf); /* blocks until the function is enabled */
        if (n < 0) { usleep(10000); continue; }    /* ESHUTDOWN while unbound: wait for rebind */
        for (ssize_t i = 0; i < n; i++) buf[i] = (uint8_t)~buf[i];
        if (write(ep_in, buf, (size_t)n) != n) { usleep(10000); continue; }
        if (++echoed % 100 == 0) printf("device: %lu packets echoed\n", echoed);
    }
}

/* ---- host side ------------------------------------------------------------------------------ */

struct link { libusb_context *ctx; libusb_device_handle *h; uint8_t ep_in, ep_out; };

static double now_s(void) { struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t); return t.tv_sec + t.tv_nsec * 1e-9; }

/* A fresh libusb context per attempt: without udevd in the guest libusb's device list is only
 * refreshed by enumeration, so a replugged device is seen by a new context. */
static int try_open(struct link *l, unsigned vid, unsigned pid) {
    if (libusb_init(&l->ctx) != 0) return 0;
    l->h = libusb_open_device_with_vid_pid(l->ctx, (uint16_t)vid, (uint16_t)pid);
    if (!l->h) { libusb_exit(l->ctx); l->ctx = NULL; return 0; }
    struct libusb_config_descriptor *cfg;
    if (libusb_get_active_config_descriptor(libusb_get_device(l->h), &cfg) != 0) FAIL("no active config");
    const struct libusb_interface_descriptor *alt = &cfg->interface[0].altsetting[0];
    l->ep_in = l->ep_out = 0;
    for (int i = 0; i < alt->bNumEndpoints; i++) {
        const struct libusb_endpoint_descriptor *e = &alt->endpoint[i];
        if ((e->bmAttributes & 3) != LIBUSB_TRANSFER_TYPE_BULK) continue;
        if (e->bEndpointAddress & LIBUSB_ENDPOINT_IN) l->ep_in = e->bEndpointAddress; else l->ep_out = e->bEndpointAddress;
        printf("host: bulk endpoint 0x%02x, max packet %u\n", e->bEndpointAddress, e->wMaxPacketSize);
    }
    libusb_free_config_descriptor(cfg);
    if (!l->ep_in || !l->ep_out) FAIL("interface 0 lacks a bulk IN and a bulk OUT endpoint");
    int r = libusb_claim_interface(l->h, 0);
    if (r != 0) FAIL("claim interface 0: %s", libusb_error_name(r));
    return 1;
}

static void close_link(struct link *l) {
    if (l->h) libusb_close(l->h);
    if (l->ctx) libusb_exit(l->ctx);
    l->h = NULL; l->ctx = NULL;
}

static void open_within(struct link *l, unsigned vid, unsigned pid, double limit_s) {
    double end = now_s() + limit_s;
    while (!try_open(l, vid, pid)) {
        if (now_s() > end) FAIL("libusb never found %04x:%04x within %.0f s", vid, pid, limit_s);
        usleep(50000);
    }
    uint8_t bus = libusb_get_bus_number(libusb_get_device(l->h)), addr = libusb_get_device_address(libusb_get_device(l->h));
    int speed = libusb_get_device_speed(libusb_get_device(l->h));
    printf("host: opened %04x:%04x at bus %u address %u, speed %d\n", vid, pid, bus, addr, speed);
}

/* Returns 0 or the libusb error of the first failing transfer. */
static int round_trips(struct link *l, int count, int size, int timeout_ms) {
    uint8_t out[4096], in[4096];
    for (int k = 0; k < count; k++) {
        for (int i = 0; i < size; i++) out[i] = (uint8_t)(k * 13 + i);
        int done = 0;
        int r = libusb_bulk_transfer(l->h, l->ep_out, out, size, &done, timeout_ms);
        if (r != 0) return r;
        if (done != size) FAIL("bulk OUT %d: %d of %d bytes", k, done, size);
        r = libusb_bulk_transfer(l->h, l->ep_in, in, sizeof in, &done, timeout_ms);
        if (r != 0) return r;
        if (done != size) FAIL("bulk IN %d: %d bytes, expected %d", k, done, size);
        for (int i = 0; i < size; i++) {
            uint8_t want = (uint8_t)(0xFFu ^ out[i]);
            if (in[i] != want) FAIL("bulk IN %d byte %d: 0x%02x, expected 0x%02x", k, i, in[i], want);
        }
    }
    return 0;
}

static void write_file(const char *path, const char *s) {
    int fd = open(path, O_WRONLY);
    if (fd < 0 || write(fd, s, strlen(s)) < 0) FAIL("write \"%s\" to %s: %s", s, path, strerror(errno));
    close(fd);
}

static int run_host(unsigned vid, unsigned pid, const char *udc_file, const char *udc) {
    struct link l = {0};
    open_within(&l, vid, pid, 20);
    int r = round_trips(&l, 100, 64, 5000);
    if (r) FAIL("64-byte round trips: %s", libusb_error_name(r));
    r = round_trips(&l, 20, 1000, 5000); /* multi-packet transfers end with a short packet */
    if (r) FAIL("1000-byte round trips: %s", libusb_error_name(r));
    printf("host: 100 x 64-byte and 20 x 1000-byte bulk round trips verified\n");

    /* Unplug: the UDC unbinds, the device leaves the bus; libusb must say so, not hang. */
    write_file(udc_file, "\n");
    double t0 = now_s();
    int err = 0;
    while (now_s() - t0 < 10 && err != LIBUSB_ERROR_NO_DEVICE) {
        err = round_trips(&l, 1, 64, 500);
        if (err) printf("host: after unbind: %s\n", libusb_error_name(err));
    }
    if (err != LIBUSB_ERROR_NO_DEVICE) FAIL("libusb did not report the unplugged device as gone (last: %s)", libusb_error_name(err));
    close_link(&l);
    if (try_open(&l, vid, pid)) FAIL("%04x:%04x can still be opened after the UDC was unbound", vid, pid);
    printf("host: unplug detected: LIBUSB_ERROR_NO_DEVICE, no longer enumerated\n");

    /* Replug: bind the UDC again; the same VID:PID comes back and works. */
    write_file(udc_file, udc);
    open_within(&l, vid, pid, 20);
    r = round_trips(&l, 50, 64, 5000);
    if (r) FAIL("round trips after replug: %s", libusb_error_name(r));
    close_link(&l);
    printf("PASS: libusb %04x:%04x bulk round trips, unplug reported, replug recovered\n", vid, pid);
    return 0;
}

int main(int argc, char **argv) {
    setvbuf(stdout, NULL, _IOLBF, 0);
    if (argc == 3 && strcmp(argv[1], "device") == 0) return run_device(argv[2]);
    if (argc == 6 && strcmp(argv[1], "host") == 0)
        return run_host((unsigned)strtoul(argv[2], NULL, 16), (unsigned)strtoul(argv[3], NULL, 16), argv[4], argv[5]);
    fprintf(stderr, "usage: %s device FFS_MOUNT | host VID PID UDC_FILE UDC_NAME\n", argv[0]);
    return 2;
}
