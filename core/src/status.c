#include "sylva/status.h"

const char *sylva_strerror(int status) {
  switch (status) {
  case SYLVA_OK: return "success";
#define SYLVA__MSG(name, msg) case SYLVA_E##name: return msg;
    SYLVA_STATUS_MAP(SYLVA__MSG)
#undef SYLVA__MSG
  default: return "unknown error";
  }
}

const char *sylva_err_name(int status) {
  switch (status) {
  case SYLVA_OK: return "SYLVA_OK";
#define SYLVA__NAME(name, msg) case SYLVA_E##name: return "SYLVA_E" #name;
    SYLVA_STATUS_MAP(SYLVA__NAME)
#undef SYLVA__NAME
  default: return "SYLVA_EUNKNOWN";
  }
}
