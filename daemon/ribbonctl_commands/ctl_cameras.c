/* ctl_cameras.c: `ribbonctl cameras [--json]`: the cameras a rig file can name in camera.source:
 * V4L2 capture devices (/dev/video*, with the driver's card name; camera.source = /dev/videoN or
 * N) and GenICam cameras Aravis finds (GigE Vision by broadcast discovery on every interface,
 * USB3 Vision; camera.source = aravis:ID). */
#include <dirent.h>
#include <fcntl.h>
#include <jansson.h>
#include <linux/videodev2.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include "ctl.h"
#include "vision.h"

typedef struct listing {
    int json;
    json_t *arr;
    int n;
} listing;

static void add(listing *l, const char *kind, const char *source, const char *vendor, const char *model,
                const char *transport)
{
    l->n++;
    if (l->json) {
        json_array_append_new(l->arr, json_pack("{s:s,s:s,s:s,s:s,s:s}", "kind", kind, "source", source, "vendor",
                                                vendor, "model", model, "transport", transport));
        return;
    }
    printf("%-8s %-32s %s %s (%s)\n", kind, source, vendor, model, transport);
}

static void v4l2_list(listing *l)
{
    DIR *d = opendir("/dev");
    if (!d) return;
    struct dirent *e;
    while ((e = readdir(d)))
        if (!strncmp(e->d_name, "video", 5)) {
            char path[300];
            snprintf(path, sizeof path, "/dev/%s", e->d_name);
            int fd = open(path, O_RDWR | O_NONBLOCK);
            if (fd < 0) continue;
            struct v4l2_capability cap;
            memset(&cap, 0, sizeof cap);
            if (ioctl(fd, VIDIOC_QUERYCAP, &cap) == 0) {
                unsigned caps = cap.capabilities & V4L2_CAP_DEVICE_CAPS ? cap.device_caps : cap.capabilities;
                if (caps & V4L2_CAP_VIDEO_CAPTURE) add(l, "v4l2", path, (const char *)cap.driver, (const char *)cap.card, (const char *)cap.bus_info);
            }
            close(fd);
        }
    closedir(d);
}

static void arv_one(void *user, const char *id, const char *vendor, const char *model, const char *protocol)
{
    char src[300];
    snprintf(src, sizeof src, "aravis:%s", id);
    add(user, "genicam", src, vendor, model, protocol);
}

int ctl_cameras_main(int argc, char **argv)
{
    listing l = {0, NULL, 0};
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--json"))
            l.json = 1;
        else if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            printf("usage: ribbonctl cameras [--json]\n"
                   "  V4L2 capture devices and GenICam (GigE Vision, USB3 Vision) cameras, with the\n"
                   "  camera.source value that opens each\n");
            return 0;
        } else {
            fprintf(stderr, "ribbonctl cameras: unknown option '%s'\n", argv[i]);
            return 2;
        }
    }
    if (l.json) l.arr = json_array();
    v4l2_list(&l);
    vis_error ve = {0};
    int rc = 0;
    if (vis_aravis_list(arv_one, &l, &ve) < 0) {
        fprintf(stderr, "ribbonctl cameras: Aravis: %s\n", ve.message);
        rc = 1;
    }
    if (l.json) {
        char *s = json_dumps(l.arr, JSON_COMPACT);
        printf("%s\n", s ? s : "[]");
        free(s);
        json_decref(l.arr);
    } else if (l.n == 0)
        printf("no cameras found\n");
    return rc;
}
