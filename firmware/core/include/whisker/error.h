/* The firmware's one error convention (STYLE.md item 8): 0 is success, a negative code names
 * the failure. Every bus and link call returns one of these and every caller checks it. */
#ifndef WHISKER_ERROR_H
#define WHISKER_ERROR_H

#define FW_OK 0
#define FW_EINVAL (-1)    /* bad argument (a null pointer, a length out of range) */
#define FW_EBUSY (-2)     /* the bus or link is still busy with an earlier transfer */
#define FW_ETIMEOUT (-3)  /* a transfer did not finish within its deadline */
#define FW_ESTART (-4)    /* MLX90333 frame: start byte is not 0xFF */
#define FW_ECHECKSUM (-5) /* MLX90333 frame: checksum mismatch */
#define FW_ECRC (-6)      /* bridge frame: CRC-16 mismatch */
#define FW_ESYNC (-7)     /* bridge frame: sync bytes missing */
#define FW_EEMPTY (-8)    /* ring: nothing to read */

/* A short constant name for a code ("FW_ETIMEOUT"), "FW_UNKNOWN" for others. */
const char *fw_strerror(int code);

#endif
