// Out-of-line anchor for the error classes (kept for ABI stability of the vtables).
#include <robocal/drivers/errors.hpp>
