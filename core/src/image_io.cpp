/* placeholder */
extern "C" { typedef int tt__placeholder_image_io; }
