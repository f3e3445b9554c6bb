<?xml version="1.0" encoding="UTF-8"?>
<physicalModel name="cells" nrOfAtoms="22" nrOfExclusiveComponents="5"
 nrOfInformativeComponents="2" nrOfCells="6">
<atoms><structuralComponent name="element list"><nrOfStructures value="22"/>
<atom><atomProperties index="10" x="0" y="0" z="0" mass="1"/></atom>
<atom><atomProperties index="20" x="10" y="0" z="0"/></atom>
<atom><atomProperties index="35" x="0" y="10" z="0"/></atom>
<atom><atomProperties index="40" x="0" y="0" z="10"/></atom>
<atom><atomProperties index="100" x="0" y="0" z="0"/></atom>
<atom><atomProperties index="101" x="0" y="0" z="10"/></atom>
<atom><atomProperties index="102" x="0" y="10" z="10"/></atom>
<atom><atomProperties index="103" x="0" y="10" z="0"/></atom>
<atom><atomProperties index="104" x="10" y="0" z="0"/></atom>
<atom><atomProperties index="105" x="10" y="0" z="10"/></atom>
<atom><atomProperties index="106" x="10" y="10" z="10"/></atom>
<atom><atomProperties index="107" x="10" y="10" z="0"/></atom>
<atom><atomProperties index="200" x="0" y="0" z="0"/></atom>
<atom><atomProperties index="201" x="10" y="0" z="0"/></atom>
<atom><atomProperties index="202" x="0" y="10" z="0"/></atom>
<atom><atomProperties index="203" x="0" y="0" z="10"/></atom>
<atom><atomProperties index="204" x="10" y="0" z="10"/></atom>
<atom><atomProperties index="205" x="0" y="10" z="10"/></atom>
<atom><atomProperties index="300" x="0" y="0" z="0"/></atom>
<atom><atomProperties index="301" x="10" y="0" z="0"/></atom>
<atom><atomProperties index="302" x="0" y="10" z="0"/></atom>
<atom><atomProperties index="303" x="10" y="10" z="0"/></atom>
</structuralComponent></atoms>
<exclusiveComponents><multiComponent name="Exclusive Components ">
<multiComponent name="Volumes">
<structuralComponent name="Tet" young="100" mode="WIREFRAME_AND_SURFACE">
<cell><cellProperties type="TETRAHEDRON" index="7"/>
<atomRef index="10"/><atomRef index="20"/><atomRef index="35"/><atomRef index="40"/></cell>
</structuralComponent>
<structuralComponent name="Hex"><nrOfStructures value="1"/>
<cell><cellProperties type="HEXAHEDRON"/>
<atomRef index="100"/><atomRef index="101"/><atomRef index="102"/><atomRef index="103"/>
<atomRef index="104"/><atomRef index="105"/><atomRef index="106"/><atomRef index="107"/></cell>
</structuralComponent>
<structuralComponent name="Wedge">
<cell><cellProperties type="WEDGE"/><atomRef index="200"/><atomRef index="201"/>
<atomRef index="202"/><atomRef index="203"/><atomRef index="204"/><atomRef index="205"/></cell>
</structuralComponent>
</multiComponent>
<structuralComponent name="Tri">
<cell><cellProperties type="TRIANGLE"/><atomRef index="300"/><atomRef index="301"/>
<atomRef index="302"/></cell></structuralComponent>
<structuralComponent name="Quad">
<cell><cellProperties type="QUAD"/><atomRef index="300"/><atomRef index="301"/>
<atomRef index="303"/><atomRef index="302"/></cell></structuralComponent>
</multiComponent></exclusiveComponents>
<informativeComponents><multiComponent name="Regions">
<structuralComponent name="Bottom Face">
<cell><cellProperties type="POLY_VERTEX"/><atomRef index="100"/><atomRef index="103"/>
<atomRef index="104"/><atomRef index="107"/></cell></structuralComponent>
<structuralComponent name="Tip"><cellRef index="7"/><atomRef index="300"/></structuralComponent>
</multiComponent></informativeComponents>
</physicalModel>
