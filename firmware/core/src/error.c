/* The error table (error.h): one name per code. */
#include "whisker/error.h"

const char *fw_strerror(int code) {
  switch (code) {
    case FW_OK:
      return "FW_OK";
    case FW_EINVAL:
      return "FW_EINVAL";
    case FW_EBUSY:
      return "FW_EBUSY";
    case FW_ETIMEOUT:
      return "FW_ETIMEOUT";
    case FW_ESTART:
      return "FW_ESTART";
    case FW_ECHECKSUM:
      return "FW_ECHECKSUM";
    case FW_ECRC:
      return "FW_ECRC";
    case FW_ESYNC:
      return "FW_ESYNC";
    case FW_EEMPTY:
      return "FW_EEMPTY";
    default:
      return "FW_UNKNOWN";
  }
}
