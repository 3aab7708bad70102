/*
 * tev.h: a client of the tev image viewer (https://github.com/Tom94/tev)
 * that shows a render as it converges (`lmc render --display-server`).
 *
 * The render thread hands it images (tev_post), which it only copies into
 * a one-slot mailbox: the newest image replaces one not yet sent. A
 * sender thread of its own connects, creates the image in the viewer and
 * sends it in tiles. Nothing it does can stall or end the render: its
 * sockets are non-blocking with deadlines, a viewer that is absent, slow
 * or gone costs a single warning on stderr (naming HOST:PORT), and the
 * sender tries again after 1 s, 2 s, 4 s, ... up to 30 s; SIGPIPE is never
 * raised. tev_destroy sends the last image posted, waiting at most the
 * time it is given.
 *
 * The protocol is tev's IPC over TCP: packets of a little-endian uint32
 * length (itself included), a uint8 type and the payload, integers
 * little-endian, strings NUL-terminated, booleans one byte:
 *   CreateImage (4): grabFocus, name, int32 width, height, nChannels,
 *     nChannels channel names;
 *   CloseImage (2): name (when the image's name changes);
 *   UpdateImageV3 (6): grabFocus, name, int32 nChannels, channel names,
 *     int32 x, y, width, height, int64 offsets[nChannels],
 *     int64 strides[nChannels], then float32 values: channel c of tile
 *     pixel p (row-major in the tile) at offsets[c] + p * strides[c].
 * lmc sends channels R, G, B, and with the error error.R, error.G,
 * error.B, interleaved (offsets 0 .. n - 1; strides n) in tiles of at most
 * TEV_TILE x TEV_TILE pixels (pbrt-v4's size), 192 or 384 KiB of values a
 * packet, well inside tev's 1 MiB receive buffer.
 */
#ifndef LMC_RENDER_IO_TEV_H
#define LMC_RENDER_IO_TEV_H

#include "render/error.h"
#include "render/image.h"

/* tev's port when the address names none. */
#define TEV_DEFAULT_PORT 14158
/* The side of the tiles sent. */
#define TEV_TILE 128
/* tev's packet types (tev's include/tev/Ipc.h). */
enum { TEV_CLOSE_IMAGE = 2, TEV_CREATE_IMAGE = 4, TEV_UPDATE_IMAGE_V3 = 6 };

typedef struct lmc_tev lmc_tev;

/* Starts a client that will show images of width x height under `name`
 * (copied; the output file's base name), with_error: and their standard
 * errors as three more channels, in the viewer at `address`,
 * "HOST[:PORT]" (options.h's lmc_address_parse; port TEV_DEFAULT_PORT when
 * none). It connects in its own thread: *OUT is ready at once. Fails only
 * on a bad address (LMC_EINVAL), no memory or no thread. */
lmc_status tev_create(lmc_tev **OUT, const char *address, const char *name, int width,
                      int height, int with_error, lmc_error *err);

/* Copies img (3 channels, the client's size; borrowed) into the mailbox,
 * with `error` (the same shape; NULL: infinite errors) when the client
 * shows the error, replacing an image not yet sent, and wakes the sender.
 * Never waits for the network. An image of another size or channel count
 * is ignored.
 * `label` (NULL or "": none; copied) follows the name in the viewer, as
 * "NAME LABEL": when it changes, the image shown under the old name is
 * closed (CloseImage) and created again under the new one. */
void tev_post(lmc_tev *t, const lmc_image *img, const lmc_image *error, const char *label);

/* Sends the image posted last if it was not sent yet (reconnecting once
 * if need be, whatever the back-off), waiting at most wait_seconds for it,
 * then closes the connection and frees t. A sender still busy after that
 * (a name lookup that hangs) is left to finish on its own and frees t
 * itself. Accepts NULL. */
void tev_destroy(lmc_tev *t, double wait_seconds);

#endif
