// bt-hls: techmap of $__BT_M9K_SDP (see bt_m9k.txt) onto one altsyncram = one M9K block in
// simple dual-port mode: port A writes, port B reads (registered address, unregistered output),
// (the generated design never reads an address in the cycle it writes it). Only parameters
// that Yosys's altsyncram blackbox declares are set.
module \$__BT_M9K_SDP (CLK1, A1ADDR, A1DATA, A1EN, B1ADDR, B1DATA, B1EN);
  parameter CFG_ABITS = 8;
  parameter CFG_DBITS = 36;
  parameter CLKPOL1 = 1;
  input CLK1;
  input [CFG_ABITS-1:0] A1ADDR;
  output [CFG_DBITS-1:0] A1DATA;
  input A1EN;
  input [CFG_ABITS-1:0] B1ADDR;
  input [CFG_DBITS-1:0] B1DATA;
  input B1EN;
  altsyncram #(
    .operation_mode("DUAL_PORT"),
    .intended_device_family("Cyclone IV E"),
    .ram_block_type("M9K"),
    .lpm_type("altsyncram"),
    .width_a(CFG_DBITS),
    .widthad_a(CFG_ABITS),
    .numwords_a(2 ** CFG_ABITS),
    .width_b(CFG_DBITS),
    .widthad_b(CFG_ABITS),
    .numwords_b(2 ** CFG_ABITS),
    .outdata_reg_b("UNREGISTERED"),
    .power_up_uninitialized("FALSE"),
    .init_type("unused")
  ) _TECHMAP_REPLACE_ (
    .clock0(CLK1),
    .clock1(1'b1),
    .address_a(B1ADDR),
    .data_a(B1DATA),
    .wren_a(B1EN),
    .rden_a(1'b0),
    .q_a(),
    .address_b(A1ADDR),
    .data_b({CFG_DBITS{1'b1}}),
    .wren_b(1'b0),
    .rden_b(A1EN),
    .q_b(A1DATA),
    .clocken0(1'b1),
    .clocken1(1'b1),
    .clocken2(1'b1),
    .clocken3(1'b1),
    .aclr0(1'b0),
    .aclr1(1'b0),
    .addressstall_a(1'b0),
    .addressstall_b(1'b0)
  );
endmodule
